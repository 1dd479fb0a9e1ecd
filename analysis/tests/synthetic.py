"""Test data in the harness's CSV format: crafted rows for exact tests and a realistic
synthetic run (fixed seed) for the figures. Nothing here is ever read as a measurement."""

from __future__ import annotations

import csv
import math
from pathlib import Path

import numpy as np

from accelbench_analysis.inputs.schema import (
    COMPILE_FLAGS_COLUMN,
    COUNT_COLUMNS,
    EMBREE_ISA_COLUMN,
    ERROR_MEMORY_VERDICT_COLUMNS,
    FP_MODE_COLUMN,
    IDENTITY_COLUMNS,
    ISA_COLUMN,
    PROVENANCE_COLUMNS,
    STATUS_COLUMNS,
    TIMING_COLUMNS,
)

# The harness's per-parameter columns, in the order the contract lists them.
PARAM_NAMES = [
    "split",
    "axis",
    "max_prims",
    "max_depth",
    "bins",
    "traversal",
    "bits",
    "threads",
    "task_threshold",
    "build",
    "isect_cost",
    "traversal_cost",
    "empty_bonus",
    "quality",
    "robust",
]

PROVENANCE = {
    "git_sha": "0123456789abcdef0123456789abcdef01234567",
    "git_dirty": "false",
    "compiler": "gcc 12.2.0",
    "build_type": "RelWithDebInfo",
    "compile_flags": "-O3 -g -DNDEBUG -march=native -mno-avx512f -ffp-contract=off",
    "cpu": "Test CPU @ 2.0GHz",
    "render_threads": "1",
    "embree_version": "3.13.5",
    "isa": "sse2+sse4.2+avx+avx2+fma",
    "embree_isa": "avx512",
    "timestamp": "2024-01-01T00:00:00Z",
    # Not provenance, but a per-row setting written just before it (after `shading`).
    "fp_mode": "ftz_daz",
}

# The harness writes the floating-point mode, the provenance columns, then `isa` and
# `embree_isa` last, and compile_flags after build_type. Files from before any of them lack
# it (drop=...).
_REQUIRED_TAIL = [FP_MODE_COLUMN] + PROVENANCE_COLUMNS + [ISA_COLUMN, EMBREE_ISA_COLUMN]
_AT = _REQUIRED_TAIL.index("build_type") + 1
PROVENANCE_TAIL = _REQUIRED_TAIL[:_AT] + [COMPILE_FLAGS_COLUMN] + _REQUIRED_TAIL[_AT:]

MODELS = {  # name: (triangles, vertices)
    "stanford-bunny": (69451, 35947),
    "igea": (268686, 134345),
    "stanford-dragon": (871414, 437645),
    "happy-buddha-100k": (100000, 49950),
    "procedural-forest": (252000, 180000),
    "procedural-city": (92000, 61000),
}


def header(with_errors: bool = False) -> list[str]:
    """The harness's header, every name once: the parameter columns (max_depth, threads)
    and the measured and global ones (tree_depth, render_threads). with_errors adds the
    optional columns (errors vs the reference, peak_rss_bytes, verdict, verdict_counts)."""
    cols = IDENTITY_COLUMNS + PARAM_NAMES + STATUS_COLUMNS + TIMING_COLUMNS + COUNT_COLUMNS
    if with_errors:
        cols += ERROR_MEMORY_VERDICT_COLUMNS
    return cols + PROVENANCE_TAIL


def row(
    model: str,
    accel: str,
    params: dict,
    *,
    build=None,
    render=None,
    nodes=None,
    prim_tests=None,
    node_visits=None,
    status="ok",
    message="",
    config="table4",
    ci=0.02,
    rays=307200,
    shadow_rays=150000,
    errors: dict | None = None,
    tree_depth=None,
    sah_cost=None,
    extra: dict | None = None,
    **provenance,
) -> dict:
    """One CSV row as a dict keyed by the header's positions (see write_csv). `extra` holds
    the values of write_csv's extra_columns (combo_id, instructions, ...); `errors` the
    values of the error, memory and verdict columns (written with write_csv(with_errors=True))."""
    tri, vert = MODELS.get(model, (1000, 600))
    canon = ";".join(f"{k}={v}" for k, v in params.items())
    r = {
        "config": config,
        "model": model,
        "triangles": tri,
        "vertices": vert,
        "accel": accel,
        "params": canon,
        "status": status,
        "message": message,
        "repetitions": 5 if status == "ok" else 0,
    }
    r["param"] = {k: params.get(k, "") for k in PARAM_NAMES}
    for name, v in (("build_s", build), ("render_s", render)):
        if v is None or status != "ok":
            for s in ("median", "mean", "stddev", "ci_lo", "ci_hi"):
                r[f"{name}_{s}"] = ""
        else:
            r.update(
                {
                    f"{name}_median": v,
                    f"{name}_mean": v * (1 + ci / 4),
                    f"{name}_stddev": v * ci,
                    f"{name}_ci_lo": v * (1 - ci),
                    f"{name}_ci_hi": v * (1 + ci),
                }
            )
    ok = status == "ok"
    r.update(
        {
            "rays": rays if ok else "",
            "hits": int(rays * 0.6) if ok else "",
            "shadow_rays": shadow_rays if ok else "",
            "shadow_hits": int(shadow_rays * 0.3) if ok else "",
            "mrays_per_s": (rays + shadow_rays) / render / 1e6 if ok and render else "",
            "nodes": "" if nodes is None else nodes,
            "leaves": "" if nodes is None else (nodes + 1) // 2,
            "tree_depth": "" if tree_depth is None else tree_depth,
            "memory_bytes": "" if nodes is None else nodes * 32,
            "sah_cost": "" if sah_cost is None else repr(sah_cost),
            "prim_tests": "" if prim_tests is None else prim_tests,
            "node_visits": "" if node_visits is None else node_visits,
        }
    )
    r["errors"] = errors or {}
    r["extra"] = extra or {}
    prov = dict(PROVENANCE)
    prov.update({k: str(v) for k, v in provenance.items()})
    r["prov"] = prov
    return r


def write_csv(
    path: Path,
    rows: list[dict],
    with_errors: bool = False,
    drop: tuple[str, ...] = (),
    extra_columns: tuple[str, ...] = (),
) -> Path:
    """Writes rows in the harness's column order (every name once); extra columns
    go before the provenance."""
    cols = header(with_errors)
    cols = cols[: -len(PROVENANCE_TAIL)] + list(extra_columns) + cols[-len(PROVENANCE_TAIL) :]
    lines = []
    for r in rows:
        vals = [r[c] for c in IDENTITY_COLUMNS]
        vals += [r["param"][p] for p in PARAM_NAMES]
        vals += [r[c] for c in STATUS_COLUMNS + TIMING_COLUMNS]
        vals += [r[c] for c in COUNT_COLUMNS]
        if with_errors:
            vals += [r["errors"].get(c, "") for c in ERROR_MEMORY_VERDICT_COLUMNS]
        vals += [r["extra"].get(c, "") for c in extra_columns]
        vals += [r["prov"][c] for c in PROVENANCE_TAIL]
        lines.append(vals)
    keep = [i for i, c in enumerate(cols) if c not in drop]
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow([cols[i] for i in keep])
        for vals in lines:
            w.writerow([vals[i] for i in keep])
    return path


# ---- a realistic run --------------------------------------------------------------------

BVH = {"split": "median", "max_prims": "1", "max_depth": "50", "bins": "16", "threads": "1"}
LBVH = {"max_prims": "1", "max_depth": "50", "bits": "30", "threads": "1"}
KD = {
    "max_prims": "1",
    "max_depth": "auto",
    "isect_cost": "80",
    "traversal_cost": "1",
    "empty_bonus": "0.5",
    "render_threads": "1",
}
SAH = {"split": "sah", "max_prims": "4", "max_depth": "64", "bins": "16", "threads": "1"}
EMBREE = {"threads": "1", "quality": "medium", "robust": "false"}


def error_counts(rng, accel: str) -> dict:
    """A row's error columns: a few wrong answers for ours (more for the kd-tree), none for
    Embree's answers."""
    errs = {
        "false_misses": int(rng.poisson(3 if accel == "kdtree" else 1)),
        "false_hits": int(rng.poisson(0.5)),
        "prim_mismatches": int(rng.poisson(2)),
        "t_err_ulp_p50": 0,
        "t_err_ulp_max": int(rng.integers(1, 8)),
        "nan_results": 0,
        "image_rmse": 0.001,
        "hole_pixels": 0,
    }
    if accel == "embree":
        errs.update(false_misses=0, false_hits=0, prim_mismatches=0)
    return errs


def table2_rows(rng, jitter) -> list[dict]:
    """Table 2's kd-tree sweeps on the bunny (max_prims, then max_depth)."""
    rows = []
    tri = MODELS["stanford-bunny"][0]
    for mp in ("1", "2", "4", "10", "30", "100"):
        p = dict(KD, max_prims=mp)
        f = float(mp)
        rows.append(
            row(
                "stanford-bunny",
                "kdtree",
                p,
                config="table2",
                build=0.15 / (1 + 0.3 * math.log10(f)) * jitter(),
                render=0.35 * (1 + 0.08 * math.log10(f) ** 2) * jitter(),
                nodes=int(5.5 * tri / f**1.2),
                prim_tests=int(4 * 457200 * f**0.9),
                node_visits=int(45 * 457200 / (1 + math.log10(f))),
                errors={"false_misses": int(rng.poisson(2)), "false_hits": 0},
            )
        )
    for d in ("5", "10", "15", "20", "28", "40", "100"):
        p = dict(KD, max_depth=d)
        dd = min(float(d), 29.0)
        rows.append(
            row(
                "stanford-bunny",
                "kdtree",
                p,
                config="table2",
                build=0.01 + 0.14 * dd / 29 * jitter(),
                render=0.33 * (1 + 40 * math.exp(-dd / 3.0)) * jitter(),
                nodes=int(min(2**dd, 5.5 * tri)),
                prim_tests=int(4 * 457200 * (1 + 3000 * math.exp(-dd / 2.2))),
                node_visits=int(45 * 457200 * dd / 29),
                errors={"false_misses": int(rng.poisson(2)), "false_hits": 0},
            )
        )
    return rows


def realistic_rows(seed: int = 7, with_errors: bool = True) -> list[dict]:
    """A plausible full run: Tables 4/5 structures on six models, Table 2 sweeps on the
    bunny, noise from a fixed seed. Orderings follow the report's findings loosely."""
    rng = np.random.default_rng(seed)

    def jitter():
        return float(rng.lognormal(0, 0.05))

    scene = {
        "stanford-bunny": 1.0,
        "igea": 0.8,
        "stanford-dragon": 1.3,
        "happy-buddha-100k": 1.0,
        "procedural-forest": 2.5,
        "procedural-city": 3.0,
    }
    cost = {  # per-structure factors: (build, render, prim tests per ray, node visits per ray)
        ("bvh", "median"): (1.0, 1.0, 9.0, 60.0),
        ("lbvh", ""): (1.6, 1.05, 9.5, 62.0),
        ("kdtree", ""): (6.0, 0.8, 4.0, 45.0),
        ("bvh", "sah"): (2.2, 0.55, 5.0, 30.0),
        ("embree", ""): (0.5, 0.2, None, None),
    }
    rows = []
    for model, (tri, _) in MODELS.items():
        lg = math.log2(tri)
        for (accel, split), (kb, kr, pt, nv) in cost.items():
            base = {"bvh": SAH if split == "sah" else BVH, "lbvh": LBVH, "kdtree": KD, "embree": EMBREE}[
                accel
            ]
            for trav in ["ordered", "report"] if accel in ("bvh", "lbvh") else [""]:
                p = dict(base)
                if trav:
                    p["traversal"] = trav
                slow = 1.25 if trav == "report" else 1.0
                rays = 307200 + 150000
                build = kb * tri * lg * 2e-9 * jitter()
                render = kr * slow * scene[model] * rays * lg * 4e-8 * jitter()
                if accel == "kdtree" and model in ("procedural-forest", "procedural-city"):
                    render *= 0.6
                nodes = (
                    None
                    if pt is None
                    else (
                        2 * tri - 1
                        if split == "median" or accel == "lbvh"
                        else int(tri * (0.6 if split == "sah" else 5.5))
                    )
                )
                errs = error_counts(rng, accel)
                rows.append(
                    row(
                        model,
                        accel,
                        p,
                        build=build,
                        render=render,
                        nodes=nodes,
                        prim_tests=None if pt is None else int(pt * slow * rays * jitter()),
                        node_visits=None if nv is None else int(nv * slow * rays * jitter()),
                        errors=errs,
                        config="table5" if "procedural" in model else "table4",
                    )
                )
    rows += table2_rows(rng, jitter)
    rows.append(
        row(
            "stanford-dragon",
            "kdtree",
            dict(KD, max_prims="1", max_depth="40"),
            status="timeout",
            message="build exceeded 600 s",
            config="table4",
        )
    )
    return rows


# ---- a robustness run (configs/robustness.yaml) -------------------------------------------

ZERO_ERRORS = {
    "false_misses": 0,
    "false_hits": 0,
    "prim_mismatches": 0,
    "nan_results": 0,
    "t_err_ulp_p50": 0,
    "t_err_ulp_max": 1,
}


def case_row(
    case: str, accel: str, params: dict, verdict: str, counts: str = "", message: str = "", status: str = "ok"
) -> dict:
    """A catalogue case's row: model `case-<id>:<name>`, a verdict, no timings."""
    r = row(
        case,
        accel,
        params,
        status=status,
        message=message,
        config="robustness",
        rays=120,
        shadow_rays=0,
        errors={"verdict": verdict, "verdict_counts": counts, "peak_rss_bytes": 50 << 20},
    )
    r["repetitions"] = ""
    return r


ROBUST_CASES = [
    "case-1a:closed-sphere-vertex-rays",
    "case-2a:closed-meshes-translated-1.5e5",
    "case-14a:nan-inf-vertices",
]
ROBUST_ACCELS = [
    ("brute_force", {}),
    ("bvh", {"split": "sah"}),
    ("lbvh", {"bits": "30"}),
    ("kdtree", {"max_prims": "1"}),
    ("embree", {"robust": "false"}),
    ("embree", {"robust": "true"}),
    ("reference", {}),
]
PASS_COUNTS = (
    "leaks=0 false_hits=0 wrong_prims=0 nan=0 occlusion_mismatches=0 nondeterministic=0 depth=12/64 rays=120"
)
EMBREE_LEAKS = (
    "leaks=3 false_hits=0 wrong_prims=0 nan=0 occlusion_mismatches=1 nondeterministic=0 depth=9/64 rays=120"
)


def robustness_rows() -> list[dict]:
    """Three cases on seven accelerator settings (Embree robust=false leaks on case 2a; the
    kd-tree refuses case 14a) plus stiff-parameter timed rows on the dragon."""
    rows = []
    for case in ROBUST_CASES:
        for accel, params in ROBUST_ACCELS:
            if case.startswith("case-2a") and accel == "embree" and params["robust"] == "false":
                rows.append(
                    case_row(
                        case,
                        accel,
                        params,
                        "fail",
                        EMBREE_LEAKS,
                        "3 rays leaked through vertices at 1.5e5 | see case 2",
                    )
                )
            elif case.startswith("case-14a") and accel == "kdtree":
                rows.append(
                    case_row(
                        case,
                        accel,
                        params,
                        "",
                        status="error",
                        message="scene rejected: NaN vertex in face 3",
                    )
                )
            else:
                rows.append(case_row(case, accel, params, "pass", PASS_COUNTS))
    dragon = "stanford-dragon"
    stiff = [
        ("kdtree", {"max_prims": "1", "max_depth": "100"}, 9.5, 0.8, 4_000_000, 100, 900),
        ("kdtree", {"max_prims": "1", "isect_cost": "10000"}, 3.1, 2.5, 20_001, 12, 400),
        ("bvh", {"split": "median", "max_depth": "1"}, 0.2, 40.0, 3, 1, 250),
        ("bvh", {"split": "median", "max_depth": "200"}, 0.3, 0.4, 1_742_827, 33, 300),
        ("embree", {"robust": "true"}, 0.1, 0.1, None, None, 260),
    ]
    for accel, params, build, render, nodes, depth, rss_mib in stiff:
        r = row(
            dragon,
            accel,
            params,
            build=build,
            render=render,
            nodes=nodes,
            tree_depth=depth,
            config="robustness",
            errors=dict(ZERO_ERRORS, peak_rss_bytes=rss_mib << 20),
        )
        rows.append(r)
    rows.append(
        row(
            dragon,
            "lbvh",
            {"bits": "1"},
            status="error",
            config="robustness",
            message="lbvh: bits=1 is below the minimum 2 (Morton codes need a bit per axis)",
        )
    )
    return rows


# The .reps.csv the harness writes beside a results CSV: one line per timed repetition.
REPS_HEADER = [
    "config",
    "combo_id",
    "model",
    "accel",
    "params",
    "repetition",
    "build_s",
    "render_s",
    "process",
]


def write_reps(path: Path, reps: list[tuple[dict, int, float, int]]) -> Path:
    """Writes (row, repetition, render_s, process) per repetition of rows made by row() with
    a combo_id in `extra` (build_s: the row's median)."""
    with path.open("w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(REPS_HEADER)
        for r, k, render, process in reps:
            key = [r["config"], r["extra"]["combo_id"], r["model"], r["accel"], r["params"]]
            w.writerow(key + [k, r["build_s_median"], render, process])
    return path
