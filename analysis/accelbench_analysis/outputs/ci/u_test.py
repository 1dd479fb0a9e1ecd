"""The two-sided Mann-Whitney U test (Mann & Whitney 1947, "On a test of whether one of two
random variables is stochastically larger than the other"), written from its definition so
the analysis needs no statistics library.

U counts, over every pair (x from A, y from B), 1 where x > y and 1/2 where they tie. With
no ties and small samples the p-value is exact: the null distribution of U is counted by
the recurrence of Mann and Whitney's paper, f(m, n, u) = f(m-1, n, u-n) + f(m, n-1, u)
(the largest of the m + n values is either an x, beating all n y's, or a y). With ties or
large samples it is the normal approximation with the tie correction of the variance and
a continuity correction (Lehmann, "Nonparametrics", 1975, ch. 1.4)."""

from __future__ import annotations

import math
from functools import cache

EXACT_LIMIT = 400  # m * n up to this, without ties: the exact distribution


@cache
def _counts(m: int, n: int) -> tuple[int, ...]:
    """The number of orderings of m x's and n y's giving each U = 0..m*n."""
    if m == 0 or n == 0:
        return (1,)
    out = [0] * (m * n + 1)
    for u, c in enumerate(_counts(m - 1, n)):
        out[u + n] += c
    for u, c in enumerate(_counts(m, n - 1)):
        out[u] += c
    return tuple(out)


def _u_statistic(a: list[float], b: list[float]) -> float:
    return sum(1.0 if x > y else 0.5 if x == y else 0.0 for x in a for y in b)


def _exact_p(u: float, m: int, n: int) -> float:
    counts = _counts(m, n)
    total = math.comb(m + n, m)
    low = min(u, m * n - u)  # the distribution is symmetric about m*n/2
    tail = sum(counts[: int(low) + 1])
    return min(1.0, 2.0 * tail / total)


def _normal_p(u: float, a: list[float], b: list[float]) -> float:
    m, n = len(a), len(b)
    ties: dict[float, int] = {}
    for v in (*a, *b):
        ties[v] = ties.get(v, 0) + 1
    big_n = m + n
    correction = sum(t**3 - t for t in ties.values()) / (big_n * (big_n - 1))
    var = m * n / 12.0 * ((big_n + 1) - correction)
    if var <= 0:
        return 1.0  # every value equal: nothing tells the samples apart
    z = (abs(u - m * n / 2.0) - 0.5) / math.sqrt(var)
    return min(1.0, math.erfc(max(z, 0.0) / math.sqrt(2.0)))


def mann_whitney_u(a: list[float], b: list[float]) -> float:
    """The two-sided p-value for "A and B come from one distribution"."""
    if not a or not b:
        raise ValueError("the U test needs at least one value on each side")
    u = _u_statistic(a, b)
    exact = len(set(a) | set(b)) == len(a) + len(b) and len(a) * len(b) <= EXACT_LIMIT
    return _exact_p(u, len(a), len(b)) if exact else _normal_p(u, a, b)


def smallest_p(m: int, n: int) -> float:
    """The smallest two-sided p-value samples of these sizes can give (every x above every
    y): below the level asked for, the test can say something; above, there are too few
    repetitions for it (3 against 3 cannot go below 0.1)."""
    return 2.0 / math.comb(m + n, m) if m and n else 1.0
