// Summary statistics of repeated timings, with a distribution-free confidence interval
// for the median.
//
// The interval comes from order statistics (the binomial method, e.g. Conover,
// "Practical Nonparametric Statistics", section 3.2): the count of samples below the true
// median is Binomial(n, 1/2), so the interval [x(k), x(n+1-k)] between the k-th smallest
// and k-th largest sample covers the median with probability
// sum_{j=k}^{n-k} C(n, j) / 2^n, whatever the distribution. It needs no resampling and
// no seed, and it is honest for the handful of repetitions a benchmark affords: we pick
// the narrowest such interval with coverage >= 95%; when n is too small for that (n < 6)
// the interval is [min, max] and `coverage` says what it really covers (0.75 for n = 3,
// 0.9375 for n = 5).
#pragma once

#include <optional>
#include <vector>

namespace accelbench {

struct Summary {
    size_t n = 0;
    double median = 0, mean = 0;
    std::optional<double> stddev;        // sample standard deviation; n >= 2
    std::optional<double> ci_lo, ci_hi;  // n >= 2
    std::optional<double> coverage;      // of [ci_lo, ci_hi]
};

constexpr double kCiLevel = 0.95;

// Throws std::invalid_argument for an empty sample.
Summary summarize(std::vector<double> samples);

// Probability that [x(k), x(n+1-k)] (1-based order statistics) covers the median.
double median_interval_coverage(size_t n, size_t k);

}  // namespace accelbench
