// Per-ray traversal statistics, free when switched off.
//
// Traversal code is templated on a counter type and calls c.node(), c.box(), c.prim().
// With NoCounters every call is an empty inline function and vanishes; with RayStats it
// increments. The choice is made once per batch of rays, not per ray, so the measured
// (uncounted) path carries no branch for it.
#pragma once

#include <cstdint>

namespace accelbench {

struct RayStats {
    uint64_t node_visits = 0;  // nodes popped/entered by the traversal
    uint64_t box_tests = 0;    // ray/box slab tests
    uint64_t prim_tests = 0;   // ray/triangle tests (the report's "#int. tests")

    void node() { ++node_visits; }
    void box(uint64_t n = 1) { box_tests += n; }
    void prim(uint64_t n = 1) { prim_tests += n; }

    RayStats& operator+=(const RayStats& o) {
        node_visits += o.node_visits;
        box_tests += o.box_tests;
        prim_tests += o.prim_tests;
        return *this;
    }
};

struct NoCounters {
    void node() {}
    void box(uint64_t = 1) {}
    void prim(uint64_t = 1) {}
};

}  // namespace accelbench
