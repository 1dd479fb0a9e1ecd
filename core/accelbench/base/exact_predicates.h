// Exact signs of the few polynomial expressions the reference structure needs, with
// floating-point expansions (Shewchuk 1997, "Adaptive Precision Floating-Point Arithmetic
// and Fast Robust Geometric Predicates").
//
// Why expansions and not a big-number library: an expansion represents a real number
// exactly as an unevaluated sum of doubles, so exact arithmetic on float inputs needs no
// dependency and no allocation beyond a small vector, and the reference keeps an
// independent check (its tests compare it with GMP's rationals).
//
// Why it is exact here: every input is a float (24-bit significand, exponent >= -149),
// so every product of up to three inputs and every rounding error term of it is far
// above double's underflow threshold (2^-1022) and far below its overflow; the
// error-free transformations below are then exact.
#pragma once

#include <cmath>
#include <stdexcept>

namespace accelbench::exact {

// An exact real number: the sum of its components, which are non-overlapping and in
// increasing magnitude (zeros removed), so the sign of the number is the sign of the last
// component and the sum of all components rounds to the number within one ulp.
// Fixed capacity, no allocation: the largest expansion built here (edge_volume: six
// products of three terms of two-component differences) has at most 96 components.
struct Expansion {
    static constexpr int kCapacity = 128;
    double c[kCapacity];
    int n = 0;

    Expansion() = default;
    Expansion(double x) { push(x); }  // NOLINT: a double is an expansion of one component
    void push(double x) {
        if (n == kCapacity) throw std::length_error("exact::Expansion: capacity exceeded");
        c[n++] = x;
    }
    bool empty() const { return n == 0; }
    double back() const { return c[n - 1]; }
    const double* begin() const { return c; }
    const double* end() const { return c + n; }
};

// a + b = s + e exactly (Knuth's TwoSum).
inline void two_sum(double a, double b, double& s, double& e) {
    s = a + b;
    const double bv = s - a;
    const double av = s - bv;
    e = (a - av) + (b - bv);
}

// a * b = p + e exactly (the fused multiply-add computes the rounding error of a * b).
inline void two_product(double a, double b, double& p, double& e) {
    p = a * b;
    e = std::fma(a, b, -p);
}

// e + b (Shewchuk's Grow-Expansion with zero elimination).
inline Expansion grow(const Expansion& e, double b) {
    Expansion h;
    double q = b;
    for (double c : e) {
        double s, err;
        two_sum(q, c, s, err);
        q = s;
        if (err != 0.0) h.push(err);
    }
    if (q != 0.0 || h.empty()) h.push(q);
    return h;
}

// e + f.
inline Expansion add(Expansion e, const Expansion& f) {
    for (double c : f) e = grow(e, c);
    return e;
}

inline Expansion negate(Expansion e) {
    for (int i = 0; i < e.n; ++i) e.c[i] = -e.c[i];
    return e;
}

// e * b (Shewchuk's Scale-Expansion with zero elimination).
inline Expansion scale(const Expansion& e, double b) {
    Expansion h;
    if (e.empty()) return {0.0};
    double q, err;
    two_product(e.c[0], b, q, err);
    if (err != 0.0) h.push(err);
    for (int i = 1; i < e.n; ++i) {
        double p, pe;
        two_product(e.c[i], b, p, pe);
        double s, se;
        two_sum(q, pe, s, se);
        if (se != 0.0) h.push(se);
        two_sum(p, s, q, err);  // p is the larger part: the fast variant would also do
        if (err != 0.0) h.push(err);
    }
    if (q != 0.0 || h.empty()) h.push(q);
    return h;
}

// e * f.
inline Expansion multiply(const Expansion& e, const Expansion& f) {
    Expansion sum{0.0};
    for (double c : f) sum = add(sum, scale(e, c));
    return sum;
}

// a - b exactly, as an expansion of at most two components.
inline Expansion difference(double a, double b) {
    double s, e;
    two_sum(a, -b, s, e);
    Expansion h;
    if (e != 0.0) h.push(e);
    if (s != 0.0 || h.empty()) h.push(s);
    return h;
}

inline int sign(const Expansion& e) {
    const double top = e.empty() ? 0.0 : e.back();
    return (top > 0.0) - (top < 0.0);
}

// The double nearest to the exact value, within one ulp (components are non-overlapping).
inline double estimate(const Expansion& e) {
    double s = 0.0;
    for (double c : e) s += c;
    return s;
}

// d . (q1 x q2) where q1 = p1 - o and q2 = p2 - o, all inputs floats held in doubles,
// evaluated exactly: the signed volume spanned by a ray direction and the two ends of a
// triangle edge seen from the ray origin (the edge function of the watertight test).
inline Expansion edge_volume(const double d[3], const double o[3], const double p1[3], const double p2[3]) {
    Expansion q1[3], q2[3];
    for (int k = 0; k < 3; ++k) {
        q1[k] = difference(p1[k], o[k]);
        q2[k] = difference(p2[k], o[k]);
    }
    Expansion sum{0.0};
    for (int k = 0; k < 3; ++k) {
        const int i = (k + 1) % 3, j = (k + 2) % 3;
        // (q1 x q2)[k] = q1[i] q2[j] - q1[j] q2[i]
        Expansion cross_k = add(multiply(q1[i], q2[j]), negate(multiply(q1[j], q2[i])));
        sum = add(sum, scale(cross_k, d[k]));
    }
    return sum;
}

}  // namespace accelbench::exact
