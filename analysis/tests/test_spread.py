"""The measured spread on crafted frames: between configs, between processes of one
config, the repetitions' interval with its coverage, and the order-statistics interval's
coverage against the binomial formula."""

from __future__ import annotations

from math import comb

import pandas as pd
import pytest

from accelbench_analysis.inputs.schema import Results
from accelbench_analysis.mapping.formatting import ci_label, repetitions_text
from accelbench_analysis.mapping.spread import claim_spread, measured_spread, median_ci, widest_gap
from accelbench_analysis.outputs.report.report import timing_lines


def results(*rows: tuple[str, str, float, float, float, float]) -> Results:
    """Rows of (combo_id, config, build median, ci_lo, ci_hi, ci_coverage)."""
    cols = ["combo_id", "config", "build_s_median", "build_s_ci_lo", "build_s_ci_hi", "ci_coverage"]
    frame = pd.DataFrame(rows, columns=cols).assign(status="ok")
    return Results(rows=frame, groups=[])


def test_between_configs_is_the_widest_gap_across_two_configs():
    # The bunny's LBVH build as the committed reference run measured it: 3.48 ms in
    # table4, 5.80 ms in scaling (67%); each row's interval is narrow.
    res = results(
        ("lbvh", "table4", 3.48, 3.20, 3.84, 0.75),
        ("lbvh", "scaling", 5.80, 5.72, 6.05, 0.75),
    )
    s = measured_spread(res, ["lbvh"], "build")["lbvh"]
    assert s.between_configs == pytest.approx(5.80 / 3.48 - 1)
    assert s.between_processes == 0
    assert s.value == s.between_configs and "2 configs" in s.how


def test_between_processes_of_one_config():
    res = results(
        ("bvh", "table4", 0.100, 0.099, 0.101, 0.969),
        ("bvh", "table4", 0.120, 0.119, 0.121, 0.969),
        ("bvh", "ablations", 0.110, 0.109, 0.111, 0.969),
    )
    s = measured_spread(res, ["bvh"], "build")["bvh"]
    assert s.between_processes == pytest.approx(0.2)
    assert s.between_configs == pytest.approx(0.1)  # ablations 0.110 against table4 0.100
    assert s.value == pytest.approx(0.2) and "processes" in s.how


def test_the_repetitions_interval_with_its_coverage():
    res = results(("kd", "table2", 0.100, 0.090, 0.104, 0.75))
    s = measured_spread(res, ["kd"], "build")["kd"]
    assert s.interval == pytest.approx(0.10) and s.coverage == 0.75
    assert s.value == pytest.approx(0.10) and "75% coverage" in s.how


def test_the_largest_part_wins_and_unmeasured_is_zero():
    res = results(
        ("a", "table4", 1.0, 0.7, 1.05, 0.75),  # interval reaches 30% below
        ("a", "scaling", 1.1, 1.09, 1.11, 0.75),
    )
    spreads = measured_spread(res, ["a", "absent"], "build")
    assert spreads["a"].value == pytest.approx(0.3)
    assert spreads["absent"].value == 0 and spreads["absent"].how == "measured once"
    assert widest_gap(res, "build").value == pytest.approx(0.3)
    assert claim_spread(res, [("a", "nodes")]).value == 0  # counts are exact


def test_the_floor_is_the_widest_gap_of_the_whole_run():
    # The claims judge table rows only; a thread-scaling row elsewhere in the run whose
    # interval reaches 85% still sets every claim's floor.
    judged = results(("a", "table4", 1.0, 0.95, 1.05, 0.969))
    run = results(("a", "table4", 1.0, 0.95, 1.05, 0.969), ("t", "thread-scaling", 1.0, 0.15, 1.2, 0.75))
    assert claim_spread(judged, [("a", "build")]).value == pytest.approx(0.05)
    floor = claim_spread(judged, [("a", "build")], run)
    assert floor.value == pytest.approx(0.85) and "widest gap" in floor.how


@pytest.mark.parametrize("n", [3, 6, 10])
def test_median_interval_coverage_against_the_binomial_formula(n):
    k, coverage = median_ci(n)
    # P(x(k) <= median <= x(n+1-k)) = P(k <= Binomial(n, 1/2) <= n - k).
    assert coverage == pytest.approx(sum(comb(n, j) for j in range(k, n - k + 1)) / 2**n)
    expected = {3: (1, 0.75), 6: (1, 0.96875), 10: (2, 0.978515625)}[n]
    assert (k, coverage) == pytest.approx(expected)
    assert (coverage >= 0.95) == (n >= 6)


def test_ci_labels_show_the_coverage_the_intervals_have():
    assert ci_label([0.75, 0.75]) == "CI 75%"
    assert ci_label([0.75, median_ci(6)[1], float("nan")]) == "CI 75-97%"
    assert ci_label([float("nan"), ""]) == ci_label([]) == "CI"  # one repetition: no interval


def with_process_gaps(res: Results, metric: str, gaps: list, processes: list) -> Results:
    """The rows with the harness's `processes` and `<metric>_s_process_gap` columns."""
    return Results(rows=res.rows.assign(processes=processes, **{f"{metric}_s_process_gap": gaps}), groups=[])


def render_results(*rows: tuple[str, str, float, float, float, float]) -> Results:
    frame = results(*rows).rows
    return Results(rows=frame.rename(columns=lambda c: c.replace("build_s", "render_s")), groups=[])


def test_the_gap_between_the_processes_that_measured_one_row():
    # Two child processes measured one row (6 repetitions pooled): their medians lie 12%
    # apart, while the pooled interval is narrow.
    res = with_process_gaps(
        render_results(("wbvh", "table4", 0.030, 0.0297, 0.0303, 0.969)), "render", [0.12], [2]
    )
    s = measured_spread(res, ["wbvh"], "render")["wbvh"]
    assert s.value == pytest.approx(0.12) and s.between_processes == pytest.approx(0.12)
    assert s.how == "render between processes: 2 processes measured one row"
    assert widest_gap(res, "render").value == pytest.approx(0.12)
    # The rows of one config still count when they differ more than a row's own processes.
    res = with_process_gaps(
        render_results(
            ("b", "table4", 0.10, 0.099, 0.101, 0.969), ("b", "table4", 0.13, 0.129, 0.131, 0.969)
        ),
        "render",
        [0.05, 0.02],
        [2, 2],
    )
    s = measured_spread(res, ["b"], "render")["b"]
    assert s.value == pytest.approx(0.3) and "processes of one config" in s.how


def test_an_unknown_process_gap_is_not_a_zero_gap():
    # Older CSVs (no column) and rows of one process (empty gap) say nothing between
    # processes: the spread is what the rows show, here the interval alone.
    one = render_results(("k", "table2", 0.100, 0.096, 0.104, 0.969))
    for res in (one, with_process_gaps(one, "render", [float("nan")], [1])):
        s = measured_spread(res, ["k"], "render")["k"]
        assert s.between_processes == 0 and s.value == pytest.approx(0.04)
        assert "interval" in s.how
    # Build's gap never stands for render's.
    res = with_process_gaps(one, "build", [0.5], [2])
    assert measured_spread(res, ["k"], "render")["k"].value == pytest.approx(0.04)


def test_repetitions_say_how_many_processes_measured_them():
    pooled = pd.DataFrame(
        {"config": "table4", "repetitions": [6, 6], "processes": [2, 2], "ci_coverage": 0.96875}
    )
    assert repetitions_text(pooled) == "6 repetitions pooled from 2 processes"
    assert repetitions_text(pooled.assign(repetitions=3, processes=1)) == "3 repetitions in one process"
    # No column (older CSVs) or an empty cell: unknown, never read as one process.
    assert repetitions_text(pooled.drop(columns="processes")) == "6 repetitions, processes not recorded"
    mixed = pd.concat([pooled, pooled.assign(repetitions=1, processes=float("nan")).iloc[:1]])
    assert repetitions_text(mixed) == (
        "2 rows of 6 repetitions pooled from 2 processes; 1 row of 1 repetition, processes not recorded"
    )
    lines = timing_lines(
        Results(
            rows=pd.concat(
                [pooled, pooled.assign(config="ray-sets", repetitions=3, processes=1, ci_coverage=0.75)]
            ).assign(status="ok"),
            groups=[],
        )
    )
    assert lines[1:] == [
        "  - table4: 6 repetitions pooled from 2 processes; CI 97%",
        "  - ray-sets: 3 repetitions in one process; CI 75%",
    ]


def test_the_run_csvs_set_the_floor_and_the_provenance_but_no_table(tmp_path):
    # The scaling config's rows are analysed by `scaling`, not `all`; they are the run's
    # all the same: a wide interval among them floors every claim's spread.
    from synthetic import realistic_rows, row, write_csv
    from test_scaling import scaling_rows

    from accelbench_analysis.commands import Sources, load

    table = write_csv(tmp_path / "table4.csv", realistic_rows(), with_errors=True)
    wide = row("dragon-10k", "bvh", {"split": "median"}, build=1.0, render=1.0, config="scaling", ci=0.9)
    rows = [*scaling_rows(), wide]
    for i, r in enumerate(rows):  # narrow intervals but the last row's
        r["extra"] = {"combo_id": f"{i:016x}", "ci_coverage": "0.75"}
    scaling = write_csv(tmp_path / "scaling.csv", rows, extra_columns=("combo_id", "ci_coverage"))
    data = load(Sources([table], run_csvs=[scaling]))
    assert "scaling" in set(data.whole_run.rows["config"])
    assert "scaling" not in set(data.everything.rows["config"]) | set(data.ranked.rows["config"])
    assert widest_gap(data.whole_run, "build").value == pytest.approx(0.9)
    assert widest_gap(data.everything, "build").value < 0.9
    alone = load(Sources([table]))
    assert alone.whole_run is alone.everything


def test_load_reads_each_csv_once_though_several_sets_share_it(tmp_path, monkeypatch):
    # The run's CSVs are in `everything` and again in `whole_run`; the reference run's
    # table4.csv in `reference` and again in `reference_run`: each file read once.
    from synthetic import realistic_rows, write_csv
    from test_scaling import scaling_rows

    from accelbench_analysis.commands import Sources, load
    from accelbench_analysis.inputs import load as load_module

    table = write_csv(tmp_path / "table4.csv", realistic_rows(), with_errors=True)
    scaling = write_csv(tmp_path / "scaling.csv", scaling_rows())
    ref_dir = tmp_path / "reference"
    (ref_dir / "csv").mkdir(parents=True)
    write_csv(ref_dir / "csv" / "table4.csv", realistic_rows(), with_errors=True)
    write_csv(ref_dir / "csv" / "scaling.csv", scaling_rows())
    reads: list[str] = []
    real = load_module.read_csv
    monkeypatch.setattr(load_module, "read_csv", lambda p: reads.append(str(p)) or real(p))
    data = load(Sources([table], reference_run=ref_dir, run_csvs=[scaling]))
    assert sorted(reads) == sorted(
        map(str, [table, scaling, ref_dir / "csv" / "table4.csv", ref_dir / "csv" / "scaling.csv"])
    )
    assert "scaling" in set(data.whole_run.rows["config"]) and "scaling" in set(
        data.reference_run.rows["config"]
    )
    assert "scaling" not in set(data.reference.rows["config"])
