#include "util/stats.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <stdexcept>

namespace accelbench {

double median_interval_coverage(size_t n, size_t k) {
    if (k == 0 || 2 * k > n) return 0.0;
    // sum_{j=k}^{n-k} C(n, j) 2^-n, in log space so large n does not underflow.
    double p = 0.0;
    for (size_t j = k; j <= n - k; ++j)
        p += std::exp(std::lgamma(double(n) + 1) - std::lgamma(double(j) + 1) - std::lgamma(double(n - j) + 1) -
                      double(n) * std::log(2.0));
    return std::min(p, 1.0);
}

Summary summarize(std::vector<double> x) {
    if (x.empty()) throw std::invalid_argument("summarize: no samples");
    std::sort(x.begin(), x.end());
    Summary s;
    s.n = x.size();
    const size_t n = s.n;
    s.median = n % 2 ? x[n / 2] : 0.5 * (x[n / 2 - 1] + x[n / 2]);
    s.mean = std::accumulate(x.begin(), x.end(), 0.0) / double(n);
    if (n < 2) return s;
    double ss = 0;
    for (double v : x) ss += (v - s.mean) * (v - s.mean);
    s.stddev = std::sqrt(ss / double(n - 1));
    // The largest k (narrowest interval) that still reaches the level; k = 1 when none does.
    size_t k = 1;
    while (2 * (k + 1) <= n && median_interval_coverage(n, k + 1) >= kCiLevel) ++k;
    s.ci_lo = x[k - 1];
    s.ci_hi = x[n - k];
    s.coverage = median_interval_coverage(n, k);
    return s;
}

}  // namespace accelbench
