"""`grid` and `grid-halve`: ranges, objectives, constraints, outputs, the second pass."""

from __future__ import annotations

import itertools
import math
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
import yaml
from PIL import Image
from synthetic import KD, row, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.grid.grid import analyse
from accelbench_analysis.grid.grid_config import (
    CHEAP,
    FINAL,
    GridConfigError,
    default_accelbench,
    load_grid_config,
    parse_objective,
)
from accelbench_analysis.grid.heatmaps import (
    heatmap_data,
    marker_position,
    published_settings,
)
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.inputs.schema import parse_params

REPO = Path(__file__).resolve().parents[2]
# The harness expands grid configs (accelbench run --dry-run=json): these tests need it built.
needs_binary = pytest.mark.skipif(
    not default_accelbench().is_file(), reason=f"{default_accelbench()} not built"
)

GRID = {"max_prims": [1, 2, 4], "max_depth": [10, 20, 30], "empty_bonus": [0, 0.5]}
# Three candidates built so that each objective has a different winner:
#           build  render   render  build+render  build+3*render
# A          10     1        1 *     11            13
# B           1     3        3        4 *          10
# C           5     1.5      1.5      6.5           9.5 *
# D           0.1   0.1      best everywhere, but 2 false misses
# everything else: build 20, render 5; one timeout.
SPECIAL = {
    (1, 30, 0.5): ("A", 10.0, 1.0),
    (4, 10, 0): ("B", 1.0, 3.0),
    (2, 20, 0.5): ("C", 5.0, 1.5),
    (4, 30, 0.5): ("D", 0.1, 0.1),
}
TIMEOUT = (1, 10, 0)
WINNERS = {"render": (1, 30, 0.5), "build+render": (4, 10, 0), "build + k * render": (2, 20, 0.5)}


def grid_config(
    tmp_path: Path, objective="build + k * render", frames=3, extra_grid=None, params=None, name="grid-test"
) -> Path:
    grid = {"objective": objective, "constraint": {"false_misses": 0}, **(extra_grid or {})}
    if frames is not None:
        grid["frames"] = frames
    doc = {
        "name": name,
        "repetitions": 1,
        "models": [{"name": "stanford-bunny"}],
        "accelerators": [
            {
                "name": "kdtree",
                "params": params
                or {
                    "max_prims": {"from": 1, "to": 4, "scale": "log2"},
                    "max_depth": {"from": 10, "to": 30, "step": 10},
                    "empty_bonus": [0, 0.5],
                    "isect_cost": 80,
                },
            }
        ],
        "grid": grid,
    }
    path = tmp_path / f"{name}-{abs(hash((objective, frames, str(extra_grid))))}.yaml"
    path.write_text(yaml.safe_dump(doc, sort_keys=False))
    return path


def grid_rows(skip=(), config="grid-test", reps=1, only=None, changes=None) -> list[dict]:
    """The grid's rows (only: just these points); changes: point -> (build, render, false
    misses) replacing the table above."""
    rows = []
    for mp, md, eb in itertools.product(*GRID.values()):
        if (mp, md, eb) in skip or (only is not None and (mp, md, eb) not in only):
            continue
        params = dict(KD, max_prims=str(mp), max_depth=str(md), empty_bonus=str(eb), isect_cost="80")
        if (mp, md, eb) == TIMEOUT:
            rows.append(
                row(
                    "stanford-bunny",
                    "kdtree",
                    params,
                    status="timeout",
                    message="build exceeded 120 s",
                    config=config,
                )
            )
            continue
        _, build, render = SPECIAL.get((mp, md, eb), ("", 20.0, 5.0))
        misses = 2 if (mp, md, eb) == (4, 30, 0.5) else 0
        build, render, misses = (changes or {}).get((mp, md, eb), (build, render, misses))
        r = row(
            "stanford-bunny",
            "kdtree",
            params,
            build=build,
            render=render,
            nodes=1001,
            config=config,
            errors={"false_misses": misses, "false_hits": 0},
        )
        r["repetitions"] = reps
        rows.append(r)
    return rows


@pytest.fixture
def grid_csv(tmp_path):
    return write_csv(tmp_path / "grid.csv", grid_rows(), with_errors=True)


def key(best_row) -> tuple:
    p = parse_params(best_row["params"])
    return (int(p["max_prims"]), int(p["max_depth"]), float(p["empty_bonus"]))


# ---- ranges and the config ------------------------------------------------------------------


@needs_binary
def test_axes_are_the_harness_expansion(tmp_path):
    """The ranges, lists and zipped groups as the harness expands them, typed as YAML reads them."""
    params = {
        "max_prims": {"from": 1, "to": 64, "scale": "log2"},
        "max_depth": {"from": 10, "to": 40, "step": 5},
        "empty_bonus": {"from": 0, "to": 0.9, "step": 0.1},
        "[isect_cost, traversal_cost]": [[80, 1], [0.5, 2.5]],
    }
    cfg = load_grid_config(grid_config(tmp_path, params=params))
    values = {tuple(a.names): a.values for a in cfg.axes}
    assert values[("max_prims",)] == [(v,) for v in (1, 2, 4, 8, 16, 32, 64)]
    assert values[("max_depth",)] == [(v,) for v in (10, 15, 20, 25, 30, 35, 40)]
    assert all(isinstance(v[0], int) for v in values[("max_prims",)] + values[("max_depth",)])
    assert values[("empty_bonus",)][3] == (0.3,)  # 12 significant digits, not 0.30000000000000004
    assert len(values[("empty_bonus",)]) == 10
    assert values[("isect_cost", "traversal_cost")] == [(80, 1), (0.5, 2.5)]
    assert cfg.combinations() == 7 * 7 * 10 * 2 and cfg.accel == "kdtree" and cfg.name == "grid-test"


@pytest.mark.parametrize(
    "spec, message",
    [
        ({"from": 4, "to": 1, "step": 1}, "`from` (4) is above `to` (1)"),
        ({"from": 0, "to": 1}, "exactly one of `step` or `scale`"),
        ({"from": 0, "to": 1, "step": 1, "scale": "log2"}, "exactly one of"),
        ({"from": 0, "to": 1, "scale": "log2"}, "a log2 range starts above 0"),
        ({"from": 0.1, "to": 1, "scale": "ln"}, "scale is log2 or log10, got 'ln'"),
        ({"from": 0, "to": 1, "step": -1}, "out of range"),
        ({"from": 0, "to": 1, "stp": 1}, "unknown key 'stp' (did you mean 'step'?)"),
        ({"from": 0, "to": 1, "step": 1e-6}, "the range has more than 10000 values"),
    ],
)
@needs_binary
def test_bad_ranges_are_refused_with_the_harness_message(tmp_path, spec, message):
    path = grid_config(tmp_path, params={"empty_bonus": spec})
    with pytest.raises(GridConfigError) as e:
        load_grid_config(path)
    assert message in str(e.value)
    assert f"{path}:" in str(e.value) and "accelerators[0].kdtree.empty_bonus" in str(e.value)


def test_without_the_harness_the_config_is_refused_naming_it(tmp_path):
    with pytest.raises(GridConfigError, match="the harness expands grid configs"):
        load_grid_config(grid_config(tmp_path), accelbench=tmp_path / "no-accelbench")


def test_objectives():
    assert parse_objective("render", None, "g").label == "render"
    assert parse_objective("build+render", None, "g").label == "build + render"
    o = parse_objective("build + k * render", 100, "g")
    assert (o.build_weight, o.render_weight) == (1.0, 100.0)
    assert parse_objective("build + 7*render", None, "g").render_weight == 7.0
    with pytest.raises(GridConfigError, match="needs `frames:`"):
        parse_objective("build + k * render", None, "g")
    with pytest.raises(GridConfigError, match="not one of"):
        parse_objective("build * render", None, "g")
    with pytest.raises(GridConfigError, match="has no k"):
        parse_objective("render", 5, "g")


@needs_binary
def test_config_errors_name_the_key(tmp_path):
    path = grid_config(tmp_path, extra_grid={"mdoe": "full"})
    with pytest.raises(GridConfigError, match=r"grid: unknown keys \['mdoe'\]"):
        load_grid_config(path)
    two = tmp_path / "two.yaml"
    two.write_text(
        "models: [{name: m}]\naccelerators: [{name: bvh}, {name: lbvh}]\ngrid: {objective: render}\n"
    )
    with pytest.raises(GridConfigError, match="exactly one accelerator"):
        load_grid_config(two)
    nogrid = tmp_path / "nogrid.yaml"
    nogrid.write_text("models: [{name: m}]\naccelerators: [{name: bvh}]\n")
    with pytest.raises(GridConfigError, match="needs a `grid:` section"):
        load_grid_config(nogrid)


@pytest.mark.parametrize("written", ["010", "0x10", "0b11", "1_000", "1:30"])
def test_integers_yaml_readers_disagree_on_are_refused(tmp_path, written):
    path = grid_config(tmp_path)
    path.write_text(path.read_text().replace("frames: 3", f"frames: {written}"))
    with pytest.raises(
        GridConfigError, match=rf"line \d+: '{written}' is written in a form YAML readers read differently"
    ):
        load_grid_config(path)


@needs_binary
def test_example_config_loads_and_counts(tmp_path):
    cfg = load_grid_config(REPO / "configs" / "grid-kdtree-bunny.yaml")
    assert cfg.accel == "kdtree" and cfg.mode == "successive_halving"
    assert [len(a.values) for a in cfg.axes] == [7, 7, 4, 1, 4]
    assert cfg.combinations() == 784 and cfg.keep == 8 and cfg.final_repetitions == 5
    assert cfg.objective.label == "build + 10 * render"


# ---- ranking ---------------------------------------------------------------------------------


@pytest.mark.parametrize("objective", list(WINNERS))
@needs_binary
def test_best_for_each_objective(tmp_path, grid_csv, objective):
    cfg = load_grid_config(grid_config(tmp_path, objective, frames=3 if "k" in objective else None))
    a = analyse(load_results([grid_csv]), cfg)
    assert key(a.best("stanford-bunny")) == WINNERS[objective]
    ranked = a.accepted("stanford-bunny")
    assert list(ranked["rank"]) == list(range(1, len(ranked) + 1))
    assert ranked["objective"].is_monotonic_increasing


@needs_binary
def test_constraint_rejects_and_says_why(tmp_path, grid_csv):
    a = analyse(load_results([grid_csv]), load_grid_config(grid_config(tmp_path)))
    d = a.ranked[
        a.ranked["params"].str.contains(
            "max_prims=4;max_depth=30;isect_cost=80;traversal_cost=1;empty_bonus=0.5"
        )
    ].iloc[0]
    assert d["rejected"] and d["reason"] == "false_misses = 2 > 0" and pd.isna(d["rank"])
    t = a.ranked[a.ranked["status"] == "timeout"].iloc[0]
    assert t["rejected"] and t["reason"] == "status timeout: build exceeded 120 s"
    assert len(a.accepted()) == 18 - 2
    assert a.constraints_checked == {"false_misses": True}


@needs_binary
def test_without_error_columns_the_constraint_is_reported_unchecked(tmp_path):
    csv = write_csv(tmp_path / "noerr.csv", grid_rows(), with_errors=False)
    a = analyse(load_results([csv]), load_grid_config(grid_config(tmp_path)))
    assert key(a.best("stanford-bunny")) == (4, 30, 0.5)  # D wins: nothing to reject it
    assert a.constraints_checked == {"false_misses": False}
    assert any("constraint false_misses <= 0 NOT CHECKED" in n and "error columns" in n for n in a.notes)


@needs_binary
def test_missing_grid_points_are_noted(tmp_path):
    csv = write_csv(tmp_path / "part.csv", grid_rows(skip=[(2, 10, 0), (2, 20, 0)]), with_errors=True)
    a = analyse(load_results([csv]), load_grid_config(grid_config(tmp_path)))
    assert (
        "stanford-bunny: 2 of the config's 18 grid points have no row (run not finished, "
        "or a shard not merged)" in a.notes
    )


@needs_binary
def test_a_second_measurement_with_more_repetitions_wins(tmp_path):
    first = write_csv(tmp_path / "p1.csv", grid_rows(), with_errors=True)
    rows = [
        r
        for r in grid_rows(config="grid-test-final", reps=5)
        if "max_prims=2;max_depth=20" in r["params"] and "empty_bonus=0.5" in r["params"]
    ]
    rows[0]["render_s_median"] = 4.0  # C measured properly: now worse than B
    second = write_csv(tmp_path / "p2.csv", rows, with_errors=True)
    cfg = load_grid_config(grid_config(tmp_path))
    a = analyse(load_results([first, second]), cfg)
    assert key(a.best("stanford-bunny")) == (4, 10, 0)  # B: 1 + 3 * 3 = 10 < 5 + 3 * 4
    assert any("set aside" in n for n in a.notes)


def test_rows_of_several_workloads_are_refused_not_ranked_together(tmp_path):
    """A grid measured on 1 and on 4 render threads: a candidate would be ranked by its
    4-thread time against another's 1-thread time (the dedupe kept one row per candidate)."""
    one = grid_rows()
    four = [dict(r, prov=dict(r["prov"], render_threads="4")) for r in grid_rows()]
    path = write_csv(tmp_path / "mixed.csv", one + four, with_errors=True)
    cfg = load_grid_config(grid_config(tmp_path))
    with pytest.raises(
        GridConfigError, match=r"holds rows of 2 workloads .*render_threads=1.0.*render_threads=4.0"
    ):
        analyse(load_results([path]), cfg)
    cheap = write_csv(tmp_path / "cheap.csv", four, with_errors=True)
    final = write_csv(tmp_path / "final.csv", one, with_errors=True)
    with pytest.raises(GridConfigError, match="the cheap pass measured another workload"):
        analyse(load_results([final]), cfg, load_results([cheap]))


def test_marker_positions():
    assert marker_position(["1", "2", "4", "8"], 4) == 2.0
    assert marker_position(["1", "2", "4", "8"], 3) == pytest.approx(1 + math.log2(1.5))
    assert marker_position(["10", "20", "30"], 29) == pytest.approx(1.9)
    assert marker_position(["10", "20", "30"], 50) is None
    assert marker_position(["median", "sah"], "sah") == 1.0
    assert marker_position(["median", "sah"], "mean") is None
    assert marker_position(["1", "2"], None) is None


def test_published_settings():
    kd = {r.label: r.values for r in published_settings("kdtree", 69451)}
    assert kd["report"]["max_depth"] == 29 and kd["pbrt-v3"]["max_depth"] == 29
    assert kd["pbrt-v3"]["isect_cost"] == 80 and kd["report"]["empty_bonus"] == 0.5
    assert {r.label: r.values for r in published_settings("kdtree", 35947)}["report"]["max_depth"] == 28
    bvh = {r.label: r for r in published_settings("bvh", 1000)}
    assert bvh["pbrt-v4"].values == {"split": "sah", "max_prims": 4}
    assert "255" in bvh["pbrt-v4"].note
    assert published_settings("embree", 1000) == []


# ---- the command line: outputs ---------------------------------------------------------------


@pytest.fixture(scope="module")
def outputs(tmp_path_factory):
    """One full `grid` run (draws the heatmaps once for all the tests below)."""
    tmp = tmp_path_factory.mktemp("grid")
    csv = write_csv(tmp / "grid.csv", grid_rows(), with_errors=True)
    cfg = grid_config(tmp)
    out = tmp / "out"
    assert main(["grid", str(csv), "--config", str(cfg), "--out", str(out)]) == 0
    return out, cfg, csv


@needs_binary
def test_heatmaps_for_each_pair(outputs):
    out, _, _ = outputs
    maps = sorted(p.name for p in out.glob("heatmap-*.png"))
    assert maps == sorted(
        [
            "heatmap-stanford-bunny-max_prims-max_depth.png",
            "heatmap-stanford-bunny-max_prims-empty_bonus.png",
            "heatmap-stanford-bunny-max_depth-empty_bonus.png",
        ]
    )
    for name in maps:
        with Image.open(out / name) as im:
            assert im.size[0] > 300 and im.size[1] > 300
            pixels = np.asarray(im.convert("RGB")).reshape(-1, 3)
            assert len(np.unique(pixels, axis=0)) > 50  # drawn, not blank


@needs_binary
def test_best_yaml_round_trips_into_a_config(outputs, tmp_path):
    out, cfg_path, _ = outputs
    doc = yaml.safe_load((out / "best.yaml").read_text())
    assert doc["objective"] == "build + 3 * render"
    assert doc["constraint"] == {"false_misses": 0} and doc["constraint_checked"] == {"false_misses": True}
    bunny = doc["best"]["stanford-bunny"]
    assert bunny["objective_s"] == pytest.approx(9.5) and bunny["accepted"] == 16
    accel = bunny["accelerators"]
    assert accel == [
        {"name": "kdtree", "params": {"max_prims": 2, "max_depth": 20, "empty_bonus": 0.5, "isect_cost": 80}}
    ]
    # Pasted into another config, the snippet is exactly that one combination.
    other = yaml.safe_load(cfg_path.read_text())
    other["accelerators"] = accel
    path = tmp_path / "uses-best.yaml"
    path.write_text(yaml.safe_dump(other))
    cfg = load_grid_config(path)
    assert cfg.points() == [{"max_prims": 2, "max_depth": 20, "empty_bonus": 0.5, "isect_cost": 80}]


@needs_binary
def test_ranked_csv(outputs):
    out, _, _ = outputs
    ranked = pd.read_csv(out / "ranked.csv")
    assert len(ranked) == 18
    assert list(ranked.columns[:8]) == [
        "model",
        "rank",
        "objective",
        "rejected",
        "reason",
        "param:max_prims",
        "param:max_depth",
        "param:empty_bonus",
    ]
    first = ranked.iloc[0]
    assert (first["rank"], first["param:max_prims"], first["param:max_depth"]) == (1, 2, 20)
    assert ranked["rejected"].sum() == 2 and ranked["rank"].isna().sum() == 2
    # Every candidate says how wrong it is: D's two false misses, the others none.
    assert {"false_hits", "prim_mismatches", "t_err_ulp_max"} <= set(ranked.columns)
    d = ranked[
        (ranked["param:max_prims"] == 4)
        & (ranked["param:max_depth"] == 30)
        & (ranked["param:empty_bonus"] == 0.5)
    ].iloc[0]
    assert d["false_misses"] == 2 and ranked["false_misses"].sum() == 2


@needs_binary
def test_summary_states_objective_and_constraints(outputs):
    out, _, _ = outputs
    text = (out / "summary.md").read_text()
    assert "objective: build + 3 * render" in text and "false_misses <= 0 (checked)" in text
    assert "| stanford-bunny | 9.50 | max_prims=2, max_depth=20, empty_bonus=0.5, isect_cost=80 |" in text
    # The winner's errors: 0 false misses and hits; wrong prims and NaN were not written (n/a).
    assert "| errors (false misses / false hits / wrong prims / NaN) |" in text
    assert "| 5.00 / 1.50 | 0 / 0 / n/a / n/a | 16 of 18 |" in text


@needs_binary
def test_grid_exit_codes(tmp_path, capsys):
    cfg = grid_config(tmp_path)
    assert main(["grid", str(tmp_path / "none.csv"), "--config", str(cfg)]) == 2
    rows = [r for r in grid_rows() if r["status"] != "ok" or r["errors"]["false_misses"]]
    csv = write_csv(tmp_path / "bad.csv", rows, with_errors=True)
    assert main(["grid", str(csv), "--config", str(cfg), "--out", str(tmp_path / "o"), "--no-heatmaps"]) == 1
    assert "no accepted candidate" in capsys.readouterr().out
    other = write_csv(
        tmp_path / "bvh.csv", [row("stanford-bunny", "bvh", {"split": "median"}, build=1, render=1)]
    )
    assert main(["grid", str(other), "--config", str(cfg), "--no-heatmaps"]) == 2
    assert "no rows of accelerator 'kdtree'" in capsys.readouterr().err


# ---- successive halving -----------------------------------------------------------------------


@needs_binary
def test_grid_halve_writes_the_second_pass(tmp_path, grid_csv, capsys):
    cfg_path = grid_config(
        tmp_path,
        extra_grid={
            "mode": "successive_halving",
            "successive_halving": {"keep": 2, "repetitions": 5, "warmup": 1},
        },
    )
    nxt = tmp_path / "next.yaml"
    assert main(["grid-halve", str(grid_csv), "--config", str(cfg_path), "--out", str(nxt)]) == 0
    assert "the second pass runs 1 x 2 = 2 combinations at 5 repetitions" in capsys.readouterr().out
    doc = yaml.safe_load(nxt.read_text())
    assert doc["name"] == "grid-test-final" and doc["repetitions"] == 5 and doc["warmup"] == 1
    params = doc["accelerators"][0]["params"]
    assert params == {"[max_prims, max_depth, empty_bonus]": [[2, 20, 0.5], [4, 10, 0]], "isect_cost": 80}
    assert list(params) == ["[max_prims, max_depth, empty_bonus]", "isect_cost"]  # config order
    assert "mode" not in doc["grid"] and doc["grid"]["halved_from"]["kept"] == 2
    second = load_grid_config(nxt)  # a valid grid config again, for `grid` on its CSV
    assert second.mode == "full" and second.combinations() == 2
    assert {(p["max_prims"], p["max_depth"]) for p in second.points()} == {(2, 20), (4, 10)}
    # --keep overrides the config; a config without keep needs --keep.
    assert (
        main(["grid-halve", str(grid_csv), "--config", str(cfg_path), "--keep", "3", "--out", str(nxt)]) == 0
    )
    assert (
        len(
            yaml.safe_load(nxt.read_text())["accelerators"][0]["params"][
                "[max_prims, max_depth, empty_bonus]"
            ]
        )
        == 3
    )
    assert main(["grid-halve", str(grid_csv), "--config", str(grid_config(tmp_path)), "--out", str(nxt)]) == 2


# ---- successive halving: the final pass ranked, the cheap pass as context ------------------------

B, C, E = (4, 10, 0), (2, 20, 0.5), (1, 20, 0)
# The cheap pass (1 repetition): the table above, plus E, which looks best of all (0.5 + 3 *
# 0.5 = 2) but was not re-measured, and (4, 30, 0) breaking the constraint like D, so the
# cell (max_prims 4, max_depth 30) holds only rejected rows; (1, 30, *) was never measured.
CHEAP_CHANGES = {E: (0.5, 0.5, 0), (4, 30, 0): (0.1, 0.1, 3)}
CHEAP_SKIP = [(1, 30, 0), (1, 30, 0.5)]


def halving_csvs(tmp_path: Path) -> tuple[Path, Path]:
    """(final, cheap): the final pass re-measures B and C at 5 repetitions; C turns out
    worse (render 4: 5 + 3 * 4 = 17) than its cheap value (9.5), B stays at 10."""
    cheap = write_csv(
        tmp_path / "pass-1.csv", grid_rows(skip=CHEAP_SKIP, changes=CHEAP_CHANGES), with_errors=True
    )
    final = write_csv(
        tmp_path / "pass-2.csv",
        grid_rows(config="grid-test-final", reps=5, only=[B, C], changes={C: (5.0, 4.0, 0)}),
        with_errors=True,
    )
    return final, cheap


def ranked_row(a, point) -> pd.Series:
    return a.ranked[[key(r) == point for _, r in a.ranked.iterrows()]].iloc[0]


@needs_binary
def test_the_best_comes_from_the_final_pass_only(tmp_path):
    final, cheap = halving_csvs(tmp_path)
    a = analyse(load_results([final]), load_grid_config(grid_config(tmp_path)), cheap=load_results([cheap]))
    best = a.best("stanford-bunny")
    assert key(best) == B and best["objective"] == pytest.approx(10.0)
    assert best["pass"] == FINAL and best["repetitions"] == 5
    e = ranked_row(a, E)  # better looking, but only cheaply measured: context, unranked
    assert e["objective"] == pytest.approx(2.0) and e["pass"] == CHEAP
    assert not e["rejected"] and pd.isna(e["rank"])
    c = ranked_row(a, C)  # measured in both passes: one row, the final values
    assert c["pass"] == FINAL and c["objective"] == pytest.approx(17.0) and c["rank"] == 2
    assert len(a.candidates()) == 2 and len(a.accepted()) == 2
    assert len(a.ranked) == 16  # 16 cheap rows, 2 of them re-measured, + 0 final-only
    assert (a.ranked["pass"] == CHEAP).sum() == 14
    assert "2 cheap-pass rows were re-measured in the final pass: their final values are used" in a.notes
    assert not any("come from config" in n for n in a.notes)  # <name>-final is expected
    # Coverage counts both passes: only (1, 30, *) is missing, not the 16 cheap-only points.
    assert (
        "stanford-bunny: 2 of the config's 18 grid points have no row (run not finished, "
        "or a shard not merged)" in a.notes
    )
    # Without --cheap, feeding both passes as ranked CSVs is what let E win: it is noted.
    both = analyse(load_results([cheap, final]), load_grid_config(grid_config(tmp_path)))
    assert key(both.best("stanford-bunny")) == E
    assert any("different repetitions (1, 5)" in n and "--cheap" in n for n in both.notes)


@needs_binary
def test_heatmap_cells_cover_the_cheap_pass_and_show_rejections(tmp_path):
    final, cheap = halving_csvs(tmp_path)
    a = analyse(load_results([final]), load_grid_config(grid_config(tmp_path)), cheap=load_results([cheap]))
    d = heatmap_data(a, "stanford-bunny", "max_prims", "max_depth")
    assert d.xs == ["1", "2", "4"] and d.ys == ["10", "20", "30"]
    obj, src = d.objective, d.source
    # The minimum over empty_bonus in every cell, from whichever pass measured it.
    assert obj.loc["10", "4"] == pytest.approx(10.0) and src.loc["10", "4"] == FINAL  # B
    assert obj.loc["20", "2"] == pytest.approx(17.0) and src.loc["20", "2"] == FINAL  # C
    assert obj.loc["20", "1"] == pytest.approx(2.0) and src.loc["20", "1"] == CHEAP  # E
    assert obj.loc["10", "1"] == pytest.approx(35.0)  # the other row timed out
    assert src.loc["10", "1"] == CHEAP and obj.notna().sum().sum() == 7
    assert d.remeasured.loc["10", "4"] and d.remeasured.loc["20", "2"]  # outlined: B, C
    assert int(d.remeasured.sum().sum()) == 2
    # (4, 30): both rows are cheap and break false_misses <= 0: rejected, not missing.
    for eb, misses in ((0, 3), (0.5, 2)):
        r = ranked_row(a, (4, 30, eb))
        assert r["pass"] == CHEAP and r["rejected"] and r["reason"] == f"false_misses = {misses} > 0"
    assert d.rejected.loc["30", "4"] and pd.isna(obj.loc["30", "4"]) and src.loc["30", "4"] == ""
    # (1, 30) has no row at all: empty, and not called rejected.
    assert pd.isna(obj.loc["30", "1"]) and not d.rejected.loc["30", "1"]
    assert int(d.rejected.sum().sum()) == 1


def test_grid_with_cheap_writes_both_passes(tmp_path):
    final, cheap = halving_csvs(tmp_path)
    out = tmp_path / "out"
    assert (
        main(
            [
                "grid",
                str(final),
                "--cheap",
                str(cheap),
                "--config",
                str(grid_config(tmp_path)),
                "--out",
                str(out),
            ]
        )
        == 0
    )
    bunny = yaml.safe_load((out / "best.yaml").read_text())
    assert bunny["csv"] == [str(final)] and bunny["cheap_csv"] == [str(cheap)]
    best = bunny["best"]["stanford-bunny"]
    assert best["objective_s"] == pytest.approx(10.0) and best["repetitions"] == 5
    assert (best["accepted"], best["candidates"]) == (2, 2)
    ranked = pd.read_csv(out / "ranked.csv")
    assert len(ranked) == 16 and list(ranked["pass"][:2]) == [FINAL, FINAL]
    assert list(ranked["rank"][:2]) == [1, 2] and ranked["rank"].notna().sum() == 2
    text = (out / "summary.md").read_text()
    assert (
        f"- final pass (ranked: the best is chosen among these only): {final}: 2 rows at "
        f"5 repetitions" in text
    )
    assert (
        f"- cheap pass (context: heatmaps and ranked.csv, never ranked): {cheap}: 16 rows "
        f"at 1 repetition; 2 of them re-measured in the final pass, the other 14 shown "
        f"with their cheap values" in text
    )
    assert "| 2 of 2 |" in text
    assert len(list(out.glob("heatmap-*.png"))) == 3


@needs_binary
def test_a_second_pass_alone_says_the_cheap_pass_is_missing(tmp_path):
    final, _ = halving_csvs(tmp_path)
    a = analyse(load_results([final]), load_grid_config(grid_config(tmp_path)))
    assert key(a.best("stanford-bunny")) == B and a.cheap is None
    assert (
        "stanford-bunny: 16 of the config's 18 grid points have no row (only the second "
        "pass was given: add the first with --cheap)" in a.notes
    )
