"""The cost model of render time (outputs/report/cost_model.py): the fit recovers a known floor
and cost per test, each sweep is fitted alone and the pooled residuals split by sweep, and
the table notes that read the claims-only rows (complete trees, what N is)."""

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


class Shifted(Sweep):
    """The depth sweep measured 5 s slower than the maxPrims sweep's line."""

    def get(self, model, structure, metric, setting="default"):
        v = super().get(model, structure, metric, setting)
        return v + 5.0 if metric == "render" and setting in cm.SWEEPS["maxDepth"] else v


def test_each_sweep_is_fitted_alone_and_a_pooled_fit_splits_by_sweep():
    src = Shifted(9.0, 0.2e-6, TESTS)
    fits = cm.fit_all(src, cl.Missing)
    assert set(fits) == {"maxPrims", "maxDepth"}  # no pooled fit
    assert fits["maxPrims"].fit.a == pytest.approx(9.0) and fits["maxDepth"].fit.a == pytest.approx(14.0)
    assert all(f.fit.r2 == pytest.approx(1.0) for f in fits.values())
    pooled = cm.pooled_residuals(src, cl.Missing)
    assert pooled["maxPrims"] < -0.5 and pooled["maxDepth"] > 0.5  # the 5 s shift, split
    text = "\n".join(cm.cost_model_lines(fits, fits, pooled))
    assert "split by sweep" in text and "Table 2 sweep" not in text
    rows = cm.cost_model_rows(list(fits.values()))
    assert list(rows.columns) == list(cm.CSV_COLUMNS) and set(rows["sweep"]) == {"maxPrims", "maxDepth"}
    assert len(rows) == 3 + 4  # each point once, labelled by its sweep
    # A sweep with a missing point is not fitted, and no pooled residuals are claimed.
    cut = Sweep(9.0, 0.2e-6, {k: v for k, v in TESTS.items() if k != "maxDepth=5"})
    assert set(cm.fit_all(cut, cl.Missing)) == {"maxPrims"} and cm.pooled_residuals(cut, cl.Missing) == {}


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
