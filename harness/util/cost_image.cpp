#include "util/cost_image.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <stdexcept>

namespace accelbench {

std::array<uint8_t, 3> inferno(double t) {
    // matplotlib's inferno sampled at 9 evenly spaced points, interpolated linearly:
    // close enough to the full table for reading a heatmap, and a few lines long.
    static constexpr double stops[9][3] = {{0.001, 0.000, 0.014}, {0.086, 0.045, 0.225}, {0.258, 0.039, 0.406},
                                           {0.416, 0.090, 0.433}, {0.578, 0.148, 0.404}, {0.735, 0.216, 0.330},
                                           {0.865, 0.317, 0.226}, {0.954, 0.469, 0.099}, {0.988, 0.645, 0.040}};
    static constexpr double top[3] = {0.988, 0.998, 0.645};  // t = 1
    t = std::clamp(std::isfinite(t) ? t : 0.0, 0.0, 1.0);
    const double x = t * 9.0;
    const int i = std::min(int(x), 8);
    const double f = x - i;
    const double* a = stops[i];
    const double* b = i + 1 < 9 ? stops[i + 1] : top;
    std::array<uint8_t, 3> rgb{};
    for (int k = 0; k < 3; ++k) rgb[size_t(k)] = uint8_t(std::lround(255.0 * (a[k] + f * (b[k] - a[k]))));
    return rgb;
}

Image heatmap(const std::vector<double>& values, int width, int height, double max) {
    if (values.size() != size_t(width) * size_t(height)) throw std::invalid_argument("heatmap: size mismatch");
    Image img(width, height);
    for (size_t i = 0; i < values.size(); ++i) {
        const auto c = inferno(max > 0 ? values[i] / max : 0.0);
        std::copy(c.begin(), c.end(), img.rgb.begin() + std::ptrdiff_t(3 * i));
    }
    return img;
}

std::vector<std::string> write_cost_images(const std::vector<RayStats>& per_pixel, int width, int height,
                                           const std::string& prefix) {
    std::vector<double> nodes(per_pixel.size()), prims(per_pixel.size());
    for (size_t i = 0; i < per_pixel.size(); ++i) {
        nodes[i] = double(per_pixel[i].node_visits);
        prims[i] = double(per_pixel[i].prim_tests);
    }
    const double node_max = *std::max_element(nodes.begin(), nodes.end());
    const double prim_max = *std::max_element(prims.begin(), prims.end());
    const std::string node_png = prefix + "-node_visits.png", prim_png = prefix + "-prim_tests.png";
    const std::string csv = prefix + "-cost.csv";
    heatmap(nodes, width, height, node_max).write_png(node_png);
    heatmap(prims, width, height, prim_max).write_png(prim_png);
    std::ofstream out(csv);
    out << "x,y,node_visits,prim_tests\n";
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const RayStats& s = per_pixel[size_t(y) * size_t(width) + size_t(x)];
            out << x << ',' << y << ',' << s.node_visits << ',' << s.prim_tests << '\n';
        }
    out.close();
    if (!out) throw std::runtime_error("writing " + csv + " failed");
    return {node_png, prim_png, csv};
}

}  // namespace accelbench
