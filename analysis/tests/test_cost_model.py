"""The cost model of render time (outputs/cost_model.py): the fit recovers a known floor and
cost per test, the floored source replaces exactly the floor, and the claims notes that
read the ablation rows (complete trees, what N is) and the ordered traversal."""

import pandas as pd
import pytest

from accelbench_analysis.outputs.report import claims as cl
from accelbench_analysis.outputs.report import cost_model as cm
from accelbench_analysis.outputs.report.table_notes import note_complete_trees


def test_fit_recovers_a_known_floor_and_cost_per_test():
    a, b = 9.5, 0.2e-6
    tests = [683_669.0, 10_571_611.0, 140_964_745.0, 2_000_000.0]
    f = cm.fit(tests, [a + b * t for t in tests])
    assert f.a == pytest.approx(a, rel=1e-9)
    assert f.b == pytest.approx(b, rel=1e-9)
    assert f.floor_tests == pytest.approx(a / b, rel=1e-9)
    assert f.r2 == pytest.approx(1.0)
    assert max(abs(r) for r in f.residuals) < 1e-9
    # A point off the line shows up in its residual, with the sign of the deviation.
    noisy = [a + b * t for t in tests]
    noisy[1] += 0.5
    g = cm.fit(tests, noisy)
    assert g.residuals[1] > 0 and g.r2 < 1


def test_fit_refuses_what_cannot_be_fitted():
    with pytest.raises(ValueError):
        cm.fit([1.0], [2.0])
    with pytest.raises(ValueError):
        cm.fit([5.0, 5.0], [1.0, 2.0])


class Sweep:
    """A claims source over the Table 2 sweeps: render = a + b * tests exactly."""

    name = "ours"

    def __init__(self, a, b, tests):
        self.a, self.b, self.tests = a, b, tests

    def begin(self):
        pass

    def groups(self):
        return set()

    def primitives(self, model):
        return 1.0

    def get(self, model, structure, metric, setting="default"):
        if (model, structure) != (cm.SWEEP_MODEL, cm.SWEEP_STRUCTURE) or setting not in self.tests:
            raise cl.Missing(setting)
        t = self.tests[setting]
        return {"prim_tests": t, "render": self.a + self.b * t, "build": 1.0}[metric]


TESTS = {s: 1e6 * (i + 1) ** 2 for i, s in enumerate(cm.SWEEPS["maxPrims"] + cm.SWEEPS["maxDepth"])}


def test_floored_source_swaps_our_floor_for_the_reports_in_tests_worth():
    report = Sweep(9.0, 0.2e-6, TESTS)  # floor: 45M tests' worth
    ours = Sweep(0.05, 5e-9, TESTS)  # floor: 10M tests' worth
    fr, fo = cm.fit_all(report, cl.Missing), cm.fit_all(ours, cl.Missing)
    assert set(fr) == {"maxPrims", "maxDepth", "Table 2"}
    floored = cm.FlooredSource(ours, fo, fr)
    s = "maxDepth=10"
    # render' = b_ours * (tests + a_report / b_report): our cost per test, the report's floor.
    assert floored.get(cm.SWEEP_MODEL, "kdtree", "render", s) == pytest.approx(5e-9 * (TESTS[s] + 45e6))
    # Everything else is ours, unchanged.
    assert floored.get(cm.SWEEP_MODEL, "kdtree", "prim_tests", s) == TESTS[s]
    assert floored.get(cm.SWEEP_MODEL, "kdtree", "build", s) == 1.0
    # A sweep that cannot be fitted on one side gives no floored source.
    with pytest.raises(ValueError):
        cm.FlooredSource(ours, {"maxPrims": fo["maxPrims"]}, fr)
    rows = cm.cost_model_rows(list(fr.values()) + list(fo.values()))
    assert list(rows.columns) == list(cm.CSV_COLUMNS)
    assert len(rows) == 2 * (3 + 4 + 7)


def test_the_floor_decides_a_ratio_claim():
    # 5.1-d, "maxPrims 1 -> 100 raises render time ~1.2x": with a negligible floor our ratio
    # is the ratio of tests; with the report's floor in tests' worth it compresses to ~1.2x.
    tests = dict(TESTS, **{"maxPrims=1": 1e6, "maxPrims=10": 2e6, "maxPrims=100": 12e6})
    ours, report = Sweep(0.001, 5e-9, tests), Sweep(20.0, 0.4e-6, tests)  # report floor 50M
    claim = next(c for c in cl.CLAIMS if c.id == "5.1-d")
    assert cl.evaluate(claim, ours).verdict == cl.FAILS
    floored = cm.FlooredSource(ours, cm.fit_all(ours, cl.Missing), cm.fit_all(report, cl.Missing))
    assert cl.evaluate(claim, floored).verdict == cl.HOLDS  # (50M + 12M) / (50M + 1M) = 1.22


def test_a_fit_that_gives_negative_times_judges_no_claim():
    # Our times falling as tests rise (b < 0, as noise over a short sweep can give):
    # render - a_ours + b_ours * floor is below zero at every setting. No floored source,
    # so no claim is judged on it.
    ours, report = Sweep(5.0, -1e-9, TESTS), Sweep(9.0, 0.2e-6, TESTS)
    fo, fr = cm.fit_all(ours, cl.Missing), cm.fit_all(report, cl.Missing)
    with pytest.raises(ValueError, match="render times <= 0"):
        cm.FlooredSource(ours, fo, fr, cl.Missing)
    # A report fit with no positive cost per test has no floor to replay.
    flat = Sweep(3.0, -1e-9, TESTS)
    with pytest.raises(ValueError, match="no positive cost per test"):
        cm.FlooredSource(
            Sweep(0.05, 5e-9, TESTS),
            cm.fit_all(Sweep(0.05, 5e-9, TESTS), cl.Missing),
            cm.fit_all(flat, cl.Missing),
            cl.Missing,
        )
    # A point the fit was not made on that replays below zero: Missing, the claim undecided.
    fine = cm.FlooredSource(
        Sweep(0.05, 5e-9, TESTS), cm.fit_all(Sweep(0.05, 5e-9, TESTS), cl.Missing), fr, cl.Missing
    )
    with pytest.raises(cl.Missing, match="gives no time"):
        fine.adjust(cm.SWEEP_MODEL, cm.SWEEP_STRUCTURE, "render", "maxDepth=10", -1.0)


def test_ordered_traversal_verdict_is_noted_where_it_differs():
    c = cl.Claim("t-1", "5.3", "kd-tree renders fastest", lambda src: (True, "x"))
    r = cl.ClaimRow(c, cl.Finding(cl.HOLDS, "r"), cl.Finding(cl.HOLDS, "ours"))
    r.verdict = cl.HOLDS
    cl.note_traversal(r, cl.Finding(cl.FAILS, "BVH 0.27 < kd-tree 0.32"))
    assert r.ordered is not None and "holds only with the report's traversal" in r.reason
    assert "BVH 0.27 < kd-tree 0.32" in r.reason
    same = cl.ClaimRow(c, cl.Finding(cl.HOLDS, "r"), cl.Finding(cl.HOLDS, "ours"))
    cl.note_traversal(same, cl.Finding(cl.HOLDS, "ours"))
    assert same.ordered is None and same.reason == ""


def test_complete_trees_note_reads_the_ablation_rows():
    report_nums = pd.DataFrame(
        [
            {"table": 5, "model": "sci-fi-city", "accelerator": "bvh", "setting": "default", "nodes": 65535},
            {"table": 5, "model": "trees", "accelerator": "bvh", "setting": "default", "nodes": 131047},
        ]
    )
    abl = pd.DataFrame(
        [
            {
                "model": "city",
                "accel": "bvh",
                "status": "ok",
                "nodes": 65535,
                "param_dict": {"split": "median", "max_depth": "15"},
            },
            {
                "model": "city",
                "accel": "bvh",
                "status": "ok",
                "nodes": 90000,
                "param_dict": {"split": "median", "max_depth": "50"},
            },
            {
                "model": "city",
                "accel": "bvh",
                "status": "ok",
                "nodes": 65535,
                "param_dict": {"split": "sah", "max_depth": "15"},
            },
        ]
    )
    text = note_complete_trees(report_nums, ["trees", "sci-fi-city"], abl)
    assert "65,535 = 2^16 - 1 nodes, a complete tree of depth 15" in text
    assert "131,047 nodes, 24 short of the complete 2^17 - 1 of depth 16" in text
    assert "city at max_depth 15: 65,535 (complete)" in text
    assert "city at max_depth 50: 90,000" in text
    assert "sah" not in text  # only median-split rows
    # No complete tree in the report's numbers: no note.
    assert note_complete_trees(report_nums[report_nums["model"] == "trees"], ["trees"], abl) is None


def test_an_ablation_on_another_model_fits_its_own_floor(tmp_path, report_nums):
    # The floor ablation at the report's Table 2 settings reads the kd-tree sweep of
    # bunny-35947 (b_e 0, primary rays, mailboxes) for the report's bunny, fits our floor on
    # those rows, and replays them with the report's floor in tests' worth.
    from synthetic import KD, row, write_csv

    from accelbench_analysis.inputs.load import load_results

    settings = {"maxPrims=1": (1, "auto"), "maxPrims=10": (10, "auto"), "maxPrims=100": (100, "auto")}
    settings.update({f"maxDepth={d}": (1, str(d)) for d in (5, 10, 28, 100)})
    a, b = 0.01, 5e-9
    rows = []
    for i, (mp, md) in enumerate(settings.values()):
        t = 1e6 * (i + 1) ** 2
        params = dict(KD, build="nlogn", max_prims=str(mp), max_depth=md, empty_bonus="0", mailbox="true")
        rows.append(
            row(
                "bunny-35947",
                "kdtree",
                params,
                build=0.1,
                render=a + b * t,
                prim_tests=t,
                config="ablations-primary",
            )
        )
        plain = dict(KD, build="nlogn", max_prims=str(mp), max_depth=md, mailbox="false")
        rows.append(
            row(
                "stanford-bunny",
                "kdtree",
                plain,
                build=0.2,
                render=1.0 + i,
                prim_tests=1e5 * (i + 1),
                config="table2",
            )
        )
    results = load_results([write_csv(tmp_path / "t2.csv", rows)])
    abl = next(x for x in cl.ABLATIONS if x.cost_model and x.models)
    assert abl.describe().endswith("on bunny-35947 for bunny")
    fits = cl.sweep_fits(results, report_nums)
    src = abl.source(results, report_nums, fits)
    report_floor = fits[0]["maxDepth"].fit.floor_tests
    t5 = 1e6 * 4**2  # maxDepth=5 is the fourth setting
    assert src.get("stanford-bunny", "kdtree", "render", "maxDepth=5") == pytest.approx(
        b * (t5 + report_floor)
    )
    assert src.get("stanford-bunny", "kdtree", "build", "maxDepth=5") == 0.1
    # The plain floor ablation reads the table's bunny rows.
    plain = next(x for x in cl.ABLATIONS if x.cost_model and not x.models)
    assert (
        plain.source(results, report_nums, fits).get("stanford-bunny", "kdtree", "build", "maxDepth=5") == 0.2
    )


def test_what_n_note_reads_the_kd_tree_at_table_3s_settings_only(tmp_path, report_nums):
    # bunny-35947 carries the kd-tree at Table 3's settings and the ablations' sweeps
    # (b_e 0, mailboxes, other depths): the note gives the first only.
    from synthetic import KD, row, write_csv

    from accelbench_analysis.inputs.load import load_results
    from accelbench_analysis.outputs.report.table_notes import note_what_n

    results = load_results(
        [write_csv(tmp_path / "t2.csv", [row("stanford-bunny", "kdtree", KD, build=1, render=1)])]
    )

    def kd(nodes, **params):
        p = {"max_prims": "1", "max_depth": "auto", "empty_bonus": "0.5", **params}
        return {"model": "bunny-35947", "accel": "kdtree", "status": "ok", "triangles": 35947, "nodes": nodes,
                "param_dict": p}  # fmt: skip

    abl = pd.DataFrame([kd(379275), kd(863569, empty_bonus="0", mailbox="true"), kd(61, max_depth="5")])
    text = note_what_n(report_nums, results, abl)
    assert "has 379,275 nodes" in text
    assert "863,569" not in text and " 61 nodes" not in text
