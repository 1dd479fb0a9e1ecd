// What the peers' plugins (tinybvh_plugin.cpp, bvh2_plugin.cpp) share: the C interface's
// error text, the resolved parameters by position, and the rule every structure keeps for a
// ray it cannot trace (accelbench_plugin.h: a non-finite, zero-direction or NaN-bounded ray
// is a miss). The libraries themselves are included from ../shared/peers, never copied here.
#pragma once

#include <accelbench/plugin/accelbench_plugin.h>

#include <cmath>
#include <cstdio>
#include <exception>

namespace peer_plugin {

inline bool traceable(const accelbench_ray& r) {
    for (int k = 0; k < 3; ++k)
        if (!std::isfinite(r.org[k]) || !std::isfinite(r.dir[k])) return false;
    return (r.dir[0] != 0 || r.dir[1] != 0 || r.dir[2] != 0) && !std::isnan(r.tmin) && !std::isnan(r.tmax);
}

inline accelbench_hit miss() { return {ACCELBENCH_INVALID_PRIM, INFINITY, 0.0f, 0.0f}; }

// Runs `f`; an exception (the libraries' allocations) becomes the C interface's error.
template <class F>
int guarded(char* error, size_t error_size, F&& f) {
    try {
        f();
        return 0;
    } catch (const std::exception& e) {
        std::snprintf(error, error_size, "%s", e.what());
        return 1;
    }
}

}  // namespace peer_plugin
