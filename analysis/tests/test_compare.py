"""`compare A B` on generated runs with realistic noise: two runs of one commit (each
process a little faster or slower than the other as a whole, each repetition noisy) flag
nothing; a 20% slowdown of one structure flags exactly its rows; counts, machines and the
U test itself."""

from __future__ import annotations

import csv
import math
import random
from pathlib import Path

import pytest
from synthetic import BVH, EMBREE, KD, LBVH, SAH, row, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.schema import ContractError
from accelbench_analysis.outputs.ci.compare import changed, compare_runs, load_run
from accelbench_analysis.outputs.ci.u_test import mann_whitney_u, smallest_p

MODELS = ["stanford-bunny", "igea", "stanford-dragon", "procedural-city"]
STRUCTURES = [
    ("embree", EMBREE, 1.0),
    ("bvh", BVH, 1.6),
    ("bvh", SAH, 1.2),
    ("lbvh", LBVH, 1.9),
    ("kdtree", KD, 1.4),
    ("wbvh", {"width": "4", "threads": "1"}, 1.1),
]
REPS = 10


def write_run(
    folder: Path, seed: int, slower: str | None = None, cpu: str = "Test CPU", nodes_of=None
) -> Path:
    """One run: every structure on every model, REPS repetitions each. The process is off
    by up to ±3% as a whole (as two processes of one build are), each repetition by 3%."""
    rng = random.Random(seed)
    whole = math.exp(rng.uniform(-0.03, 0.03))
    rows, reps = [], []
    for m, model in enumerate(MODELS):
        for i, (accel, params, cost) in enumerate(STRUCTURES):
            combo = f"c{m}{i}"
            slow = 1.2 if accel == slower else 1.0
            render = [
                0.05 * (m + 1) * cost * whole * slow * math.exp(rng.gauss(0, 0.03)) for _ in range(REPS)
            ]
            build = [0.02 * (m + 1) * cost * whole * math.exp(rng.gauss(0, 0.03)) for _ in range(REPS)]
            r = row(
                model,
                accel,
                params,
                build=1,
                render=1,
                nodes=1001,
                prim_tests=5000,
                extra={"combo_id": combo},
            )
            for name, samples in (("render_s", render), ("build_s", build)):
                s = sorted(samples)
                # The median with the order-statistic 95% interval of ten samples (ranks 2 and 9).
                r[f"{name}_median"] = (s[4] + s[5]) / 2
                r[f"{name}_ci_lo"], r[f"{name}_ci_hi"] = s[1], s[8]
            if nodes_of and (model, accel) == nodes_of:
                r["nodes"] = 1003
            r["prov"]["cpu"] = cpu
            rows.append(r)
            reps += [
                [r["config"], combo, model, accel, r["params"], k + 1, build[k], render[k]]
                for k in range(REPS)
            ]
    folder.mkdir(parents=True)
    path = write_csv(folder / "table4.csv", rows, extra_columns=("combo_id",))
    with (folder / "table4.reps.csv").open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(["config", "combo_id", "model", "accel", "params", "repetition", "build_s", "render_s"])
        w.writerows(reps)
    return path


def test_u_test_against_known_values():
    assert mann_whitney_u([1, 2, 3, 4, 5], [6, 7, 8, 9, 10]) == pytest.approx(2 / 252)
    # U = 2 of 25 for 5 against 5: p = 2 * (1 + 1 + 2) / 252, the tables' 0.0317.
    assert mann_whitney_u([1, 2, 3, 4, 7], [5, 6, 8, 9, 10]) == pytest.approx(8 / 252)
    assert mann_whitney_u([1, 1, 1], [1, 1, 1]) == 1.0
    assert smallest_p(3, 3) == pytest.approx(0.1)  # three against three can never say < 0.05


def test_two_runs_of_one_commit_flag_nothing(tmp_path):
    a, b = write_run(tmp_path / "a", 1), write_run(tmp_path / "b", 2)
    c = compare_runs(load_run(a.parent), load_run(b.parent), "a", "b")
    assert len(c.pairs) == len(MODELS) * len(STRUCTURES) >= 20
    assert all(len(p.times) == 2 and all(t.p is not None for t in p.times) for p in c.pairs)
    assert changed(c) == []
    assert not any(p.counts for p in c.pairs)


def test_a_slower_structure_is_flagged_and_no_other(tmp_path):
    a, b = write_run(tmp_path / "a", 1), write_run(tmp_path / "b", 2, slower="kdtree")
    c = compare_runs(load_run(a.parent), load_run(b.parent), "a", "b")
    flagged = changed(c)
    assert {p.key for p, _ in flagged} == {p.key for p in c.pairs if "kdtree" in p.key}
    assert len(flagged) == len(MODELS)
    assert all(t.measure == "trace" and 1.1 < t.ratio < 1.35 and t.p < 0.01 for _, t in flagged)
    assert main(["compare", str(a), str(b), "--fail-above", "1.1", "--out", str(tmp_path / "out")]) == 1
    assert main(["compare", str(a), str(b), "--fail-above", "1.5"]) == 0
    text = (tmp_path / "out" / "compare.md").read_text()
    assert text.count("**changed**") == len(MODELS)
    assert (tmp_path / "out" / "compare.html").read_text().startswith("<!DOCTYPE html>")


def test_changed_counts_are_listed_apart_from_times(tmp_path):
    a = write_run(tmp_path / "a", 1)
    b = write_run(tmp_path / "b", 2, nodes_of=("igea", "lbvh"))
    c = compare_runs(load_run(a), load_run(b), "a", "b")
    assert [(p.counts) for p in c.pairs if p.counts] == [[("nodes", 1001.0, 1003.0)]]
    assert changed(c) == []


def test_machines_are_never_compared(tmp_path):
    a = write_run(tmp_path / "a", 1)
    b = write_run(tmp_path / "b", 2, cpu="Other CPU")
    with pytest.raises(ContractError, match="share no machine"):
        compare_runs(load_run(a), load_run(b), "a", "b")
    assert main(["compare", str(a), str(b)]) == 2


def test_too_few_repetitions_are_said(tmp_path):
    a, b = write_run(tmp_path / "a", 1), write_run(tmp_path / "b", 2)
    for path in (a, b):  # keep three repetitions of each
        reps = path.with_name("table4.reps.csv")
        lines = reps.read_text().splitlines()
        reps.write_text("\n".join([lines[0]] + [x for x in lines[1:] if int(x.split(",")[-3]) <= 3]) + "\n")
    c = compare_runs(load_run(a), load_run(b), "a", "b")
    assert all(t.p is None and not t.changed for p in c.pairs for t in p.times)
