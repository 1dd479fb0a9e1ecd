"""The claims' classes and reasons (outputs/claims.py classify), one synthetic case per class,
the run's timing spread, and the claims.csv columns the issue fixes."""

import pandas as pd
from synthetic import BVH, KD, LBVH, write_csv
from synthetic import row as row_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.inputs.schema import Results
from accelbench_analysis.outputs.report import claims as cl


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


# ---- one synthetic CSV per class, through write_claims to claims.csv --------------------

TABLE4 = (("stanford-bunny", 1.0), ("igea", 4.0), ("stanford-dragon", 12.0), ("happy-buddha-100k", 2.0))


def table4_rows(lbvh_build, config="table4"):
    """Table 3's three structures on Table 4's models; lbvh_build(model) is the LBVH's build
    time relative to the BVH's."""
    out = []
    for m, f in TABLE4:
        out += [
            row_csv(m, "bvh", BVH, build=0.1 * f, render=1.0 * f, config=config),
            row_csv(m, "lbvh", LBVH, build=0.1 * f * lbvh_build(m), render=1.0 * f, config=config),
            row_csv(m, "kdtree", KD, build=0.9 * f, render=0.8 * f, config=config),
        ]
    return out


def claims_csv(tmp_path, name, rows, report_nums):
    for r in rows:  # one id per combination, as the harness writes (model, structure, parameters)
        r["extra"].setdefault("combo_id", f"{r['model']}/{r['accel']}/{r['params']}")
    path = write_csv(tmp_path / f"{name}.csv", rows, extra_columns=("combo_id",))
    cl.write_claims(load_results([path]), report_nums, tmp_path / name)
    return pd.read_csv(tmp_path / name / "claims.csv", keep_default_na=False).set_index("claim")


def test_csv_implementation_an_ablation_reproduces(tmp_path, report_nums):
    # Our LBVH builds in half the BVH's time: "BVH builds fastest" (5.2-a) fails. The
    # ablation rows measure the LBVH at build=median beside the BVH: 1.1x the BVH's.
    rows = table4_rows(lambda m: 0.5)
    for m, f in TABLE4:
        rows += [
            row_csv(m, "bvh", BVH, build=0.1 * f, render=1.0 * f, config="ablations"),
            row_csv(
                m, "lbvh", dict(LBVH, build="median"), build=0.11 * f, render=1.0 * f, config="ablations"
            ),
        ]
    c = claims_csv(tmp_path, "implementation", rows, report_nums).loc["5.2-a"]
    assert (c["verdict"], c["class"], c["ablation_verdict"]) == (cl.FAILS, "implementation", "holds")
    assert (
        "lbvh build=median; bvh at Table 3's settings" in c["ablation"]
        and "BVH 0.100 < LBVH 0.110" in c["ablation_value"]
    )
    assert c["reason"].startswith("holds at the report's LBVH as measured")


def test_csv_within_noise_from_the_gap_between_two_configs(tmp_path, report_nums):
    # The LBVH builds 4% faster than the BVH on the bunny only; the bunny's kd-tree was
    # measured in two configs 10% apart: the run's spread covers the 4%.
    rows = table4_rows(lambda m: 0.96 if m == "stanford-bunny" else 1.5)
    rows += [row_csv("stanford-bunny", "kdtree", KD, build=0.99, render=0.88, config="table2")]
    for r in rows:
        if r["model"] == "stanford-bunny" and r["accel"] == "kdtree":
            r["extra"] = {"combo_id": "kd-bunny"}
    c = claims_csv(tmp_path, "noise", rows, report_nums).loc["5.2-a"]
    assert (c["verdict"], c["class"]) == (cl.WITHIN_NOISE, "noise")
    assert "10% between two configs" in c["reason"]
    # Without the second measurement the spread is the repetitions' (2%): the 4% is a
    # difference.
    c = claims_csv(
        tmp_path, "no-noise", table4_rows(lambda m: 0.96 if m == "stanford-bunny" else 1.5), report_nums
    )
    assert (c.loc["5.2-a", "verdict"], c.loc["5.2-a", "class"]) == (cl.FAILS, "implementation")


def test_csv_stand_in_and_report_numbers(tmp_path, report_nums):
    # Trees and City on the procedural stand-ins: the LBVH spends twice the BVH's total
    # (5.3-d fails, read on stand-ins only) and the kd-tree renders 1.5x faster than both
    # (5.3-b: "more than 2x" fails, as on the report's own numbers: 1.84x).
    rows = []
    for m in ("procedural-forest", "procedural-city"):
        rows += [
            row_csv(m, "bvh", BVH, build=0.1, render=1.5, config="table5"),
            row_csv(m, "lbvh", LBVH, build=0.2, render=3.0, config="table5"),
            row_csv(m, "kdtree", KD, build=0.9, render=1.0, config="table5"),
        ]
    c = claims_csv(tmp_path, "stand-in", rows, report_nums)
    assert (c.loc["5.3-d", "verdict"], c.loc["5.3-d", "class"]) == (cl.FAILS, "stand-in")
    assert "Trees → procedural-forest" in c.loc["5.3-d", "reason"]
    assert (c.loc["5.3-b", "verdict"], c.loc["5.3-b", "class"]) == (cl.FAILS, "report-numbers")
    assert "1.84x" in c.loc["5.3-b", "reason"]
