"""`regress`: crafted baseline/current pairs that pass and fail each tier, and bad input."""

from __future__ import annotations

import copy

import pytest
from synthetic import BVH, EMBREE, KD, LBVH, PROVENANCE, row, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.ci.regress import compare, embree_ratios, keyed

EXTRA = ("combo_id", "instructions")


def ci_rows() -> list[dict]:
    """A small CI run: four structures on the bunny and the forest, with exact counts."""
    spec = [
        ("bvh", BVH, 0.30, 138901, 1.2e9),
        ("kdtree", KD, 0.24, 402113, 0.9e9),
        ("lbvh", LBVH, 0.33, 138901, 1.3e9),
        ("embree", EMBREE, 0.06, None, 2.5e8),
    ]
    rows = []
    for m, model in enumerate(("stanford-bunny", "procedural-forest")):
        for i, (accel, params, render, nodes, instr) in enumerate(spec):
            counted = nodes is not None
            rows.append(
                row(
                    model,
                    accel,
                    params,
                    build=0.1,
                    render=render * (1 + m),
                    nodes=nodes,
                    prim_tests=1_234_567 + i if counted else None,
                    node_visits=9_876_543 + i if counted else None,
                    tree_depth=28 if counted else None,
                    sah_cost=61.234567891234 + i if counted else None,
                    config="ci",
                    extra={"combo_id": f"{m}{i}aa55aa55aa55aa", "instructions": int(instr)},
                )
            )
    return rows


def find(rows, model, accel):
    return next(r for r in rows if r["model"] == model and r["accel"] == accel)


@pytest.fixture
def run(tmp_path):
    """run(name, mutate) writes ci_rows() after mutate(rows) as name.csv."""

    def make(name, mutate=None, extra=EXTRA, **kw):
        rows = ci_rows()
        if mutate:
            mutate(rows)
        return write_csv(tmp_path / f"{name}.csv", rows, extra_columns=extra, **kw)

    return make


def regress(base, cur, *more, capsys=None):
    code = main(["regress", "--baseline", str(base), "--current", str(cur), *map(str, more)])
    out = capsys.readouterr().out if capsys else ""
    return code, out


def test_identical_run_passes_and_shows_provenance(run, capsys):
    code, out = regress(run("base"), run("cur"), capsys=capsys)
    assert code == 0
    assert out.startswith("# Regression check: PASS")
    assert PROVENANCE["git_sha"] in out and PROVENANCE["cpu"] in out and "gcc 12.2.0" in out
    assert "matched by combo_id" in out
    assert "8 combinations compared: 0 above +10%" in out  # tier 2 covers Embree too
    assert "| 1. Deterministic counts | pass |" in out


def test_changed_node_count_fails_with_a_table(run, capsys):
    def more_nodes(rows):
        find(rows, "stanford-bunny", "kdtree")["nodes"] += 1
        find(rows, "procedural-forest", "bvh")["prim_tests"] = 1_234_600

    code, out = regress(run("base"), run("cur", more_nodes), capsys=capsys)
    assert code == 1
    assert out.startswith("# Regression check: FAIL")
    assert "| stanford-bunny / kdtree | nodes | 402,113 | 402,114 | 1.0000 |" in out
    assert "| procedural-forest / bvh | prim_tests | 1,234,567 | 1,234,600 | 1.0000 |" in out
    assert "2 values changed in 2 combinations" in out


def test_embree_answers_are_shown_not_failed(run, capsys):
    def embree_differs(rows):
        r = find(rows, "stanford-bunny", "embree")
        r["shadow_hits"] = int(r["shadow_hits"]) + 1

    code, out = regress(run("base"), run("cur", embree_differs), capsys=capsys)
    assert code == 0
    assert "third-party answers, not compared exactly" in out
    assert "stanford-bunny / embree shadow_hits" in out


@pytest.mark.parametrize(
    "metric", ["leaves", "tree_depth", "hits", "shadow_hits", "rays", "shadow_rays", "node_visits"]
)
def test_every_exact_count_is_checked(run, metric):
    def bump(rows):
        r = find(rows, "stanford-bunny", "bvh")
        r[metric] = int(r[metric]) + 1

    assert regress(run("base"), run("cur", bump))[0] == 1


def test_sah_cost_relative_tolerance(run, capsys):
    def nudge(factor):
        def f(rows):
            r = find(rows, "stanford-bunny", "lbvh")
            r["sah_cost"] = repr(float(r["sah_cost"]) * factor)

        return f

    assert regress(run("base"), run("tiny", nudge(1 + 1e-12)), capsys=capsys)[0] == 0
    code, out = regress(run("base"), run("big", nudge(1 + 1e-7)), capsys=capsys)
    assert code == 1 and "| stanford-bunny / lbvh | sah_cost | 63.23456789 |" in out


def test_counter_appearing_where_baseline_had_none_is_a_change(run, capsys):
    def counted_embree(rows):
        find(rows, "stanford-bunny", "embree")["prim_tests"] = 5

    code, out = regress(run("base"), run("cur", counted_embree), capsys=capsys)
    assert code == 1 and "| stanford-bunny / embree | prim_tests | (empty) | 5 |" in out


def test_missing_combination_fails_added_one_is_reported(run, capsys):
    code, out = regress(run("base"), run("cur", lambda rows: rows.pop(2)), capsys=capsys)
    assert code == 1
    assert "Missing from this run (a failure: the baseline measured them): stanford-bunny / lbvh" in out

    def added(rows):
        extra = copy.deepcopy(find(rows, "stanford-bunny", "bvh"))
        extra["params"] = extra["params"].replace("max_prims=1", "max_prims=4")
        extra["param"]["max_prims"] = "4"
        extra["extra"]["combo_id"] = "ffffffffffffffff"
        rows.append(extra)

    code, out = regress(run("base"), run("more", added), capsys=capsys)
    assert code == 0
    assert "New in this run (not in the baseline; not compared): stanford-bunny / bvh (max_prims=4)" in out


def test_status_change_fails(run, capsys):
    def timeout(rows):
        i = rows.index(find(rows, "procedural-forest", "kdtree"))
        r = rows[i]
        rows[i] = row(
            r["model"],
            "kdtree",
            KD,
            status="timeout",
            message="build exceeded 600 s",
            config="ci",
            extra=r["extra"],
        )

    code, out = regress(run("base"), run("cur", timeout), capsys=capsys)
    assert code == 1
    assert "| procedural-forest / kdtree | status | ok | timeout: build exceeded 600 s |" in out


def scale_instructions(factor, model="stanford-bunny", accel="bvh"):
    def f(rows):
        r = find(rows, model, accel)
        r["extra"]["instructions"] = int(r["extra"]["instructions"] * factor)

    return f


@pytest.mark.parametrize(
    "factor, code, text",
    [
        (1.09, 0, "| stanford-bunny / bvh | 1,200,000,000 | 1,308,000,000 | 1.0900 | pass |"),
        (1.11, 1, "| stanford-bunny / bvh | 1,200,000,000 | 1,332,000,000 | 1.1100 | FAIL |"),
        (0.89, 0, "| stanford-bunny / bvh | 1,200,000,000 | 1,068,000,000 | 0.8900 | improved"),
    ],
)
def test_instruction_tier(run, capsys, factor, code, text):
    got, out = regress(run("base"), run("cur", scale_instructions(factor)), capsys=capsys)
    assert got == code
    assert text in out
    assert ("run `make update-baseline`" in out) == (factor < 1)


def test_instruction_tolerance_option(run, capsys):
    base, cur = run("base"), run("cur", scale_instructions(1.09))
    assert regress(base, cur, "--instructions-tolerance", "0.05", capsys=capsys)[0] == 1


def test_instructions_not_measured_is_reported_not_failed(run, capsys):
    code, out = regress(run("base"), run("cur", extra=("combo_id",)), capsys=capsys)
    assert code == 0
    assert "not measured in this run" in out
    code, out = regress(run("b2", extra=("combo_id",)), run("c2", extra=("combo_id",)), capsys=capsys)
    assert (
        code == 0 and "| 2. Instruction counts (callgrind Ir of the measured render) | not checked |" in out
    )


def slower(factor, model="stanford-bunny", accel="kdtree"):
    def f(rows):
        r = find(rows, model, accel)
        for s in ("median", "mean", "ci_lo", "ci_hi"):
            r[f"render_s_{s}"] *= factor

    return f


def test_time_within_factor_passes(run, capsys):
    code, out = regress(run("base"), run("cur", slower(1.4)), capsys=capsys)
    assert code == 0
    # bunny kd-tree: 0.24 / 0.06 = 4 in the baseline, 0.336 / 0.06 = 5.6 now
    assert "| stanford-bunny / kdtree | 4.00 | 5.60 | 1.4000 | pass |" in out


def test_whole_machine_slower_cancels_in_the_ratio(run, capsys):
    def everything_slower(rows):
        for r in rows:
            for s in ("median", "mean", "ci_lo", "ci_hi"):
                r[f"render_s_{s}"] *= 3

    assert regress(run("base"), run("cur", everything_slower), capsys=capsys)[0] == 0


def test_single_time_exceedance_asks_for_a_second_measurement(run, capsys):
    code, out = regress(run("base"), run("cur", slower(2.0)), capsys=capsys)
    assert code == 3
    assert out.startswith("# Regression check: NEEDS A SECOND MEASUREMENT")
    assert "exceeded once, no previous measurement given (--history): measure again" in out
    assert "--history FIRST.csv" in out


def test_two_consecutive_exceedances_fail(run, capsys):
    base, first, second = run("base"), run("first", slower(1.8)), run("second", slower(2.0))
    code, out = regress(base, second, "--history", first, capsys=capsys)
    assert code == 1
    assert "| stanford-bunny / kdtree | 4.00 | 8.00 | 2.0000 | 7.20 | FAIL |" in out


def test_a_baseline_from_before_the_flags_is_compared_and_says_so(run, capsys):
    # Regress compares builds on purpose; a baseline without compile_flags is not refused.
    code, out = regress(run("base", drop=("compile_flags",)), run("cur"), capsys=capsys)
    assert code == 0 and out.startswith("# Regression check: PASS")
    assert "(flags unknown)" in out and f"(flags {PROVENANCE['compile_flags']})" in out
    assert "built with different compiler flags (baseline: ['unknown']; current: [" in out


def test_exceedance_after_a_good_measurement_is_a_warning(run, capsys):
    base, first, second = run("base"), run("first"), run("second", slower(2.0))
    code, out = regress(base, second, "--history", first, capsys=capsys)
    assert code == 0
    assert "exceeded once (the previous measurement was within): warning" in out


def test_time_factor_option(run, capsys):
    base, cur = run("base"), run("cur", slower(1.4))
    assert regress(base, cur, "--time-factor", "1.2", capsys=capsys)[0] == 3
    assert regress(base, cur, "--time-factor", "1", capsys=capsys)[0] == 2


def test_a_failure_outranks_a_pending_time_measurement(run, capsys):
    def both(rows):
        slower(2.0)(rows)
        find(rows, "stanford-bunny", "bvh")["nodes"] += 2

    assert regress(run("base"), run("cur", both), capsys=capsys)[0] == 1


def test_embree_denominator_is_same_model_and_render_settings(tmp_path):
    rows = ci_rows()
    robust = copy.deepcopy(find(rows, "stanford-bunny", "embree"))
    robust["params"] = robust["params"].replace("robust=false", "robust=true")
    robust["param"]["robust"] = "true"
    robust["render_s_median"] = 0.5
    robust["extra"]["combo_id"] = "eeeeeeeeeeeeeeee"
    rows.append(robust)
    wide = copy.deepcopy(find(rows, "stanford-bunny", "bvh"))
    wide["extra"].update(combo_id="dddddddddddddddd", image_width="1024")
    rows.append(wide)
    cols = ("combo_id", "instructions", "image_width")
    for r in rows:
        r["extra"].setdefault("image_width", "640")
    # "image_width" differs between the two bvh rows, so their (config, model, accel, params) key
    # repeats; the harness's combo_id tells them apart. Load through a renamed config.
    rows_by_config = [dict(r, config="ci-wide") if r is wide else r for r in rows]
    path = write_csv(tmp_path / "run.csv", rows_by_config, extra_columns=cols)
    res = load_results([path])
    ratios = embree_ratios(res, True, str(path))
    bunny_bvh = ratios["00aa55aa55aa55aa"]
    assert bunny_bvh.ratio == pytest.approx(0.30 / 0.06)  # robust=false sorts first
    assert "robust=false" in bunny_bvh.denominator
    assert ratios["dddddddddddddddd"].denominator == "no Embree row with this model and render settings"
    assert set(keyed(res.rows, True, "x")) >= set(ratios)


def test_without_combo_id_the_contract_key_matches(run, capsys):
    base, cur = run("base", extra=("instructions",)), run("cur", extra=("instructions",))
    code, out = regress(base, cur, capsys=capsys)
    assert code == 0 and "matched by (config, model, accel, params)" in out
    cmp = compare(base, run("c2", lambda rows: rows.pop(0), extra=("instructions",)))
    assert cmp.exit_code == 1


def test_report_file_equals_printed_report(run, tmp_path, capsys):
    target = tmp_path / "sub" / "report.md"
    code, out = regress(run("base"), run("cur", slower(2.0)), "--report", target, capsys=capsys)
    assert code == 3 and target.read_text() == out


def test_bad_input_exits_2(run, tmp_path, capsys):
    base = run("base")
    assert regress(base, tmp_path / "nope.csv")[0] == 2
    assert "nope.csv: no such file" in capsys.readouterr().err
    broken = run("broken", drop=("node_visits",))
    assert regress(base, broken)[0] == 2
    assert "missing required columns: node_visits" in capsys.readouterr().err

    def duplicate_id(rows):
        rows[1]["extra"]["combo_id"] = rows[0]["extra"]["combo_id"]

    assert regress(base, run("dup", duplicate_id))[0] == 2
    assert "occurs more than once" in capsys.readouterr().err


def test_error_counts_are_exact_counts_where_the_baseline_has_them(tmp_path, capsys):
    def write(name, misses, with_errors=True):
        rows = ci_rows()
        for r in rows:
            r["errors"] = {"false_misses": 0, "false_hits": 0, "prim_mismatches": 0, "nan_results": 0}
        find(rows, "stanford-bunny", "lbvh")["errors"]["false_misses"] = misses
        return write_csv(tmp_path / f"{name}.csv", rows, with_errors=with_errors, extra_columns=EXTRA)

    assert regress(write("base", 0), write("same", 0), capsys=capsys)[0] == 0
    code, out = regress(write("base", 0), write("leaky", 3), capsys=capsys)
    assert code == 1 and "| stanford-bunny / lbvh | false_misses | 0 | 3 |" in out
    # An older baseline without the columns: not compared, and said so.
    code, out = regress(write("old", 0, with_errors=False), write("leaky", 3), capsys=capsys)
    assert code == 0 and "Error columns not in the baseline, so not compared: false_hits, false_misses" in out
