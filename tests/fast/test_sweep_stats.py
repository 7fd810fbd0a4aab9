"""The confidence intervals of a sweep's report (usarsim.sweep.stats): Garwood's exact
Poisson interval against its published values, t intervals clipped to the range a score can
take, and each score of the report getting the interval suited to it."""

from __future__ import annotations

import math

import pytest

from usarsim.sweep.report import INTERVALS, Stat, method_of
from usarsim.sweep.results import SCORE_COLUMNS
from usarsim.sweep.stats import poisson_cdf, poisson_interval, poisson_total_interval, t_interval

# Garwood's 95 % limits for an observed count (Garwood 1936; the same as chi2(0.025, 2k) / 2
# and chi2(0.975, 2k + 2) / 2 of the usual tables)
GARWOOD = {
    0: (0.0, 3.689),
    1: (0.0253, 5.572),
    2: (0.2422, 7.225),
    5: (1.6235, 11.668),
    10: (4.7954, 18.390),
    100: (81.364, 121.627),
}


@pytest.mark.parametrize("count", sorted(GARWOOD))
def test_the_exact_poisson_interval_has_garwoods_published_limits(count):
    low, high = poisson_total_interval(count)
    assert low == pytest.approx(GARWOOD[count][0], abs=5e-4)
    assert high == pytest.approx(GARWOOD[count][1], abs=5e-3)
    # and its defining property: 2.5 % of the Poisson beyond the count at each end
    assert poisson_cdf(count, high) == pytest.approx(0.025, abs=1e-9)
    if count:
        assert 1.0 - poisson_cdf(count - 1, low) == pytest.approx(0.025, abs=1e-9)


def test_the_poisson_cdf_sums_without_overflow():
    assert poisson_cdf(0, 2.0) == pytest.approx(math.exp(-2.0))
    assert poisson_cdf(2, 2.0) == pytest.approx(math.exp(-2.0) * (1 + 2 + 2))
    assert poisson_cdf(3000, 3000.0) == pytest.approx(0.5, abs=0.01)  # e^-3000 alone underflows
    assert poisson_cdf(5, 0.0) == 1.0


def test_a_count_per_run_never_gets_a_negative_limit():
    # victims found 1, 0, 1 in three runs: Student's t would say [-0.77, 2.10]
    t = t_interval([1.0, 0.0, 1.0])
    assert t is not None and t[0] == pytest.approx(-0.768, abs=1e-3)
    low, high = poisson_interval([1.0, 0.0, 1.0])
    assert (low, high) == pytest.approx((0.2422 / 3, 7.2247 / 3), abs=1e-4)
    assert low > 0.0
    # none found: from 0, and still an interval (a t interval would have no width)
    assert poisson_interval([0.0, 0.0, 0.0]) == pytest.approx((0.0, 3.6889 / 3), abs=1e-4)
    assert poisson_interval([2.0]) == pytest.approx((0.2422, 7.2247), abs=1e-4)  # one run
    assert poisson_interval([]) is None
    assert poisson_interval([0.0, 0.0], high=1.0) == pytest.approx((0.0, 1.0))  # at most the team's size


def test_a_t_interval_is_clipped_to_the_range_of_the_score():
    area = [0.0, 0.0, 30.0]  # m²: mean 10, the t interval reaches -31.6
    raw = t_interval(area)
    assert raw is not None and raw[0] < -30.0
    low, high = t_interval(area, low=0.0)
    assert low == 0.0 and high == pytest.approx(raw[1])
    share = [1.0, 1.0, 0.8]  # radio contact share: the t interval reaches 1.22
    raw = t_interval(share)
    assert raw is not None and raw[1] > 1.2 and 0.6 < raw[0] < 0.7
    assert t_interval(share, low=0.0, high=1.0) == (raw[0], 1.0)
    assert t_interval([1.0, 1.0, 0.4], low=0.0, high=1.0) == (0.0, 1.0)  # past both ends
    assert t_interval([5.0]) is None


def test_every_score_of_the_report_has_an_interval_suited_to_it():
    assert set(INTERVALS) == set(SCORE_COLUMNS)
    counts = ("victims_found", "victims_reported", "false_reports", "collisions", "robots_lost")
    assert all(INTERVALS[m][0] == "poisson" for m in counts)
    assert INTERVALS["score"] == ("t", None, None)  # penalties: a score can be negative
    assert INTERVALS["area_m2"] == ("t-clipped", 0.0, None)
    assert INTERVALS["radio_contact_share"] == ("t-clipped", 0.0, 1.0)
    assert method_of("victims_found") == "exact Poisson (Garwood)"
    assert method_of("area_m2") == "Student's t, clipped at 0"
    assert method_of("radio_contact_share") == "Student's t, clipped to [0, 1]"
    # a negative score keeps its negative interval; a count's never goes below 0
    s = Stat.of([-20.0, -5.0, 10.0], "score")
    assert s.ci_low < -20.0 and s.method == "t"
    c = Stat.of([0.0, 0.0, 3.0], "collisions")
    assert c.ci_low == pytest.approx(0.6187 / 3, abs=1e-3) and c.sd == pytest.approx(math.sqrt(3.0))
    lost = Stat.of([0.0, 0.0, 0.0], "robots_lost", team_size=2)
    assert (lost.ci_low, lost.ci_high) == pytest.approx((0.0, 1.2296), abs=1e-3)
    assert Stat.of([0.0, 0.0, 0.0], "robots_lost", team_size=1).ci_high == pytest.approx(1.0)
