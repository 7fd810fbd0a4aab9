"""The 95 % confidence intervals of a sweep's report, each suited to what its score can be
(docs/experiments.md, "The statistics"):

* **Student's t** for the combined score, which can be any number (its penalties make it
  negative): mean ± t(0.975, n - 1) x s / sqrt(n) (Student, "The probable error of a mean",
  Biometrika 6(1), 1908).
* **Student's t, clipped to the possible range** for a score bounded by nature: the area
  explored and the distance travelled (at least 0), the radio contact share (0 to 1).  The
  true mean lies in the range, so cutting off the part of the interval outside it never makes
  the interval miss the mean more often (Mandelkern, "Setting confidence intervals for
  bounded parameters", Statistical Science 17(2), 2002).
* **The exact Poisson interval** for counts (victims found and reported, false reports,
  collisions, robots lost): for the total S of n runs, the means mu whose Poisson
  distribution (of n x mu) puts at most 2.5 % on each side of S: P(X >= S) = 0.025 at the
  lower end (0 when S is 0), P(X <= S) = 0.025 at the upper end (Garwood, "Fiducial limits
  for the Poisson distribution", Biometrika 28(3/4), 1936).  It never goes below 0, and it
  exists for one run or a count that never varied, where a t interval has no width.

No SciPy: the t quantiles are tabulated, the Poisson tails summed and solved by bisection.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

# The interval methods, by name.
T = "t"
T_CLIPPED = "t-clipped"
POISSON = "poisson"

# How each method is named for people (tables' footnotes, plots' titles).
METHOD_NAMES = {
    T: "Student's t",
    T_CLIPPED: "Student's t, clipped to the possible range",
    POISSON: "exact Poisson (Garwood)",
}

# Student's t, two-sided 95 % (the 0.975 quantile), by degrees of freedom; beyond 30 it is
# interpolated in 1/df towards the normal's 1.960.
_T975 = (
    12.706,
    4.303,
    3.182,
    2.776,
    2.571,
    2.447,
    2.365,
    2.306,
    2.262,
    2.228,
    2.201,
    2.179,
    2.160,
    2.145,
    2.131,
    2.120,
    2.110,
    2.101,
    2.093,
    2.086,
    2.080,
    2.074,
    2.069,
    2.064,
    2.060,
    2.056,
    2.052,
    2.048,
    2.045,
    2.042,
)
_T975_FAR = ((30, 2.042), (40, 2.021), (60, 2.000), (120, 1.980), (math.inf, 1.960))

ALPHA = 0.05  # two-sided: 2.5 % on each side


def t975(df: int) -> float:
    """The 0.975 quantile of Student's t with ``df`` degrees of freedom (df >= 1)."""
    if df < 1:
        raise ValueError(f"degrees of freedom must be >= 1, got {df}")
    if df <= len(_T975):
        return _T975[df - 1]
    for (d0, t0), (d1, t1) in zip(_T975_FAR, _T975_FAR[1:]):
        if df <= d1:
            a, b = 1.0 / d0, (0.0 if math.isinf(d1) else 1.0 / d1)
            return t0 + (t1 - t0) * (a - 1.0 / df) / (a - b)
    return 1.960


def t_interval(
    values: Sequence[float], low: float | None = None, high: float | None = None
) -> tuple[float, float] | None:
    """The 95 % t interval of the mean of ``values`` (None for fewer than two), clipped to
    [``low``, ``high``] where given."""
    n = len(values)
    if n < 2:
        return None
    mean = sum(values) / n
    sd = math.sqrt(sum((v - mean) ** 2 for v in values) / (n - 1))
    half = t975(n - 1) * sd / math.sqrt(n)
    lo, hi = mean - half, mean + half
    if low is not None:
        lo, hi = max(lo, low), max(hi, low)
    if high is not None:
        lo, hi = min(lo, high), min(hi, high)
    return lo, hi


def poisson_cdf(k: int, mu: float) -> float:
    """P(X <= k) for X Poisson with mean ``mu`` (k >= 0, mu >= 0)."""
    if mu <= 0.0:
        return 1.0
    # the terms mu^i e^-mu / i!, summed from the largest down in log space: no overflow
    logs = [i * math.log(mu) - mu - math.lgamma(i + 1) for i in range(k + 1)]
    top = max(logs)
    return min(1.0, math.exp(top) * sum(math.exp(v - top) for v in logs))


def _solve_mean(k: int, target: float) -> float:
    """The mean mu at which P(X <= k) = ``target`` (the CDF falls as mu grows)."""
    lo, hi = 0.0, max(10.0, 2.0 * k + 10.0)
    while poisson_cdf(k, hi) > target:
        hi *= 2.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if poisson_cdf(k, mid) > target:
            lo = mid
        else:
            hi = mid
        if hi - lo <= 1e-10 * max(1.0, hi):
            break
    return 0.5 * (lo + hi)


def poisson_total_interval(total: int) -> tuple[float, float]:
    """Garwood's exact 95 % interval of a Poisson mean from one count ``total``."""
    if total < 0:
        raise ValueError(f"a count is >= 0, got {total}")
    lower = 0.0 if total == 0 else _solve_mean(total - 1, 1.0 - ALPHA / 2)  # P(X >= total) = 2.5 %
    upper = _solve_mean(total, ALPHA / 2)  # P(X <= total) = 2.5 %
    return lower, upper


def poisson_interval(values: Sequence[float], high: float | None = None) -> tuple[float, float] | None:
    """The exact 95 % interval of the mean count per run of ``values`` (counts of n runs;
    None for none), clipped at ``high`` where given (robots lost: the team's size)."""
    n = len(values)
    if n == 0:
        return None
    total = int(round(sum(values)))
    lo, hi = poisson_total_interval(total)
    lo, hi = lo / n, hi / n
    if high is not None:
        lo, hi = min(lo, high), min(hi, high)
    return lo, hi
