"""The claims' classes and reasons (outputs/claims.py classify), one synthetic case per class,
the run's timing spread, and the claims.csv columns the issue fixes."""

import pandas as pd

from accelbench_analysis.inputs.schema import Results
from accelbench_analysis.outputs import claims as cl


class FakeSource:
    """Our side over a dict {(model, structure, metric): value}; stand-ins by a map."""

    def __init__(self, values, stand_in=None):
        self.values, self.stand_in = values, stand_in or {}

    def begin(self):
        pass

    def groups(self):
        return {"A"}

    def primitives(self, model):
        return 1000.0

    def model(self, report_model):
        return self.stand_in.get(report_model, report_model)

    def get(self, model, structure, metric, setting="default"):
        return self.values[(model, structure, metric)]


def faster(src):
    """A claim of the shape 'BVH renders faster than LBVH on the bunny'."""
    return cl.compare(src, ["stanford-bunny"], "bvh", "lbvh", "render")


CLAIM = cl.Claim("t-1", "5.2", "BVH renders faster than LBVH", faster)


def row(ours_holds: bool, report_holds: bool = True, models=("stanford-bunny",)):
    v = lambda h: cl.Finding(cl.HOLDS if h else cl.FAILS, "evidence")  # noqa: E731
    r = cl.ClaimRow(CLAIM, v(report_holds), v(ours_holds))
    r.models_used = set(models)
    return r


def slow_bvh(bvh=1.02, lbvh=1.0):
    return FakeSource({("stanford-bunny", "bvh", "render"): bvh, ("stanford-bunny", "lbvh", "render"): lbvh})


def test_report_numbers_when_the_reports_own_numbers_fail_too():
    r = row(False, report_holds=False)
    cl.classify(r, slow_bvh(2.0), 0.0, "none", [])
    assert (r.verdict, r.cls) == (cl.FAILS, "report-numbers")
    assert "report's own numbers" in r.reason


def test_implementation_when_an_ablation_holds():
    abl = cl.ABLATIONS[0]
    r = row(False, report_holds=False)
    cl.classify(r, slow_bvh(2.0), 0.0, "none", [(abl, cl.Finding(cl.HOLDS, "nodes 61"))])
    assert (r.cls, r.ablation_verdict_holds) == ("implementation", True)
    out = r.csv_row()
    assert (out["ablation_verdict"], out["ablation_value"]) == ("holds", "nodes 61")
    assert out["ablation"].startswith("configs/ablations.yaml")


def test_within_noise_from_a_spread_and_not_without_it():
    r = row(False)
    cl.classify(r, slow_bvh(1.02, 1.0), 0.05, "5% between configs", [])
    assert (r.verdict, r.cls) == (cl.WITHIN_NOISE, "noise")
    r = row(False)
    cl.classify(r, slow_bvh(1.02, 1.0), 0.0, "none", [])
    assert (r.verdict, r.cls) == (cl.FAILS, "implementation")
    # A gap far beyond the spread is not noise.
    r = row(False)
    cl.classify(r, slow_bvh(1.5, 1.0), 0.05, "5%", [])
    assert r.cls == "implementation"


def test_stand_in_when_the_claim_reads_only_stand_ins():
    src = FakeSource({("trees", "bvh", "render"): 2.0, ("trees", "lbvh", "render"): 1.0}, {"trees": "forest"})
    r = row(False, models=("trees",))
    cl.classify(r, src, 0.0, "none", [])
    assert r.cls == "stand-in" and "forest" in r.reason


def test_by_construction_replaces_a_hold_that_cannot_fail():
    c = cl.Claim("t-2", "5.2", "2N-1 nodes", faster, by_construction="2N-1 for one primitive per leaf")
    r = cl.ClaimRow(c, cl.Finding(cl.HOLDS, "e"), cl.Finding(cl.HOLDS, "e"))
    cl.classify(r, slow_bvh(), 0.0, "none", [])
    assert (r.verdict, r.cls) == (cl.BY_CONSTRUCTION, "")
    assert [x.id for x in cl.CLAIMS if x.by_construction] == ["5.2-g"]


def test_summary_counts_each_class():
    a, b = row(False, report_holds=False), row(False)
    cl.classify(a, slow_bvh(2.0), 0.0, "none", [])
    cl.classify(b, slow_bvh(1.02), 0.05, "5%", [])
    line = cl.summary_line([a, b])
    assert line.startswith("Of 2 claims that do not hold at our settings: 0 reproduced under an ablation, ")
    assert "1 contradicted by the report's own tables" in line and "1 within noise" in line


def test_timing_spread_takes_the_widest_gap_between_configs():
    rows = pd.DataFrame(
        {
            "config": ["table2", "table4", "table4"],
            "combo_id": ["k", "k", "other"],
            "status": ["ok"] * 3,
            "build_s_median": [1.0, 1.0, 1.0],
            "render_s_median": [1.0, 1.13, 2.0],
        }
    )
    spread, how = cl.timing_spread(Results(rows=rows, groups=[]))
    assert abs(spread - 0.13) < 1e-9 and "two configs" in how


def test_csv_columns_are_the_issues():
    assert cl.CSV_COLUMNS == (
        "claim", "text", "report_value", "our_value", "verdict", "class", "reason",
        "ablation", "ablation_value", "ablation_verdict",
    )  # fmt: skip
