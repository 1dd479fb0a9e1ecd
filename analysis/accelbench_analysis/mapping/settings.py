"""The settings every claim is judged at: our defaults, the faithful setting (every reading
of the report at once, configs/faithful.yaml) and one setting per factor switched back
from faithful to our default.

A row belongs to a setting by its config, its structure's parameters and its model label,
all declared here: nothing is inferred from which rows happen to exist. The evidence for
each reading is in configs/faithful.yaml and docs/decisions.md ("The faithful setting and
its factors").
"""

from __future__ import annotations

from dataclasses import dataclass

Params = tuple[tuple[str, str], ...]

# The configs whose rows are judged by the claims only (never shown in the report's
# tables): the faithful setting and its factors, and the older ablations.
FAITHFUL_CONFIGS = ("faithful", "quick-faithful")
UNSHADED_CONFIGS = ("faithful-unshaded", "quick-faithful-unshaded")
ABLATION_CONFIGS = ("ablations", "quick-ablations", "ablations-primary", "quick-ablations-primary")
CLAIMS_ONLY_CONFIGS = FAITHFUL_CONFIGS + UNSHADED_CONFIGS + ABLATION_CONFIGS

DEFAULT, FAITHFUL = "default", "faithful"

# The report's published code, where it is the evidence for a reading.
PUBLISHED_CODE = (
    "the report's published code (github.com/Alhajras/Raytracer-Data-structures, "
    "project/raytracer/accelerators.h at 7435d41, a spheres-only version not shown to have "
    "produced the report's tables)"
)


@dataclass(frozen=True)
class Setting:
    name: str
    # What differs from the faithful setting, in words ("" for faithful and default).
    factor: str = ""
    # The configs whose rows it reads; empty: every config but CLAIMS_ONLY_CONFIGS.
    configs: tuple[str, ...] = ()
    # Per structure (bvh, lbvh, kdtree), the parameter values its rows must have.
    params: tuple[tuple[str, Params], ...] = ()
    # Per (report model, structure), parameter values that replace the structure's.
    model_params: tuple[tuple[str, str, Params], ...] = ()
    # Report model -> our model labels, the first present in the setting's rows wins.
    models: tuple[tuple[str, tuple[str, ...]], ...] = ()
    # A labelled variant whose claims cannot fail: a claim that holds only here is
    # `by construction`, never reproduced.
    by_construction: str = ""
    # The evidence for the faithful reading this setting switches back, where it is cited.
    evidence: str = ""

    def params_of(self, structure: str, report_model: str) -> Params:
        base = dict(dict(self.params).get(structure, ()))
        for m, s, ps in self.model_params:
            if m == report_model and s == structure:
                base.update(ps)
        return tuple(base.items())


def _with(
    params: tuple[tuple[str, Params], ...], structure: str, **values: str
) -> tuple[tuple[str, Params], ...]:
    out = []
    for s, ps in params:
        if s == structure:
            ps = tuple({**dict(ps), **values}.items())
        out.append((s, ps))
    return tuple(out)


FAITHFUL_PARAMS: tuple[tuple[str, Params], ...] = (
    ("kdtree", (("build", "pbrt"), ("empty_bonus", "0"), ("mailbox", "true"))),
    ("bvh", (("traversal", "report"),)),
    ("lbvh", (("build", "report"), ("traversal", "report"))),
)
CITY_CAP: tuple[tuple[str, str, Params], ...] = (("sci-fi-city", "bvh", (("max_depth", "15"),)),)
REPORT_UNIT_MODELS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("stanford-bunny", ("bunny-35947",)),
    ("trees", ("forest-252178v", "forest-60000v")),
    ("sci-fi-city", ("city-90811v", "city-40000v")),
)
OUR_UNIT_MODELS: tuple[tuple[str, tuple[str, ...]], ...] = (
    ("stanford-bunny", ("stanford-bunny",)),
    ("trees", ("forest",)),
    ("sci-fi-city", ("city",)),
)


def _factor(name: str, factor: str, **kw) -> Setting:
    base = dict(
        configs=FAITHFUL_CONFIGS, params=FAITHFUL_PARAMS, model_params=CITY_CAP, models=REPORT_UNIT_MODELS
    )
    base.update(kw)
    return Setting(name, factor, **base)


SETTINGS: list[Setting] = [
    Setting(DEFAULT, "our defaults (the table configs)"),
    _factor(FAITHFUL, ""),
    _factor(
        "b_e=0.5",
        "kd-tree empty bonus 0.5",
        params=_with(FAITHFUL_PARAMS, "kdtree", empty_bonus="0.5"),
        evidence=f"faithful b_e 0: {PUBLISHED_CODE} declares `char emptyBonus = 0.5f`, which stores 0",
    ),
    _factor(
        "kd-tree build=nlogn",
        "kd-tree events sorted once (ours), not at every node (pbrt's)",
        params=_with(FAITHFUL_PARAMS, "kdtree", build="nlogn"),
        evidence=f"faithful build=pbrt: the report follows pbrt (its 4.2); {PUBLISHED_CODE} sorts at every node",
    ),
    _factor(
        "lbvh build=karras",
        "LBVH built by Karras 2012",
        params=_with(FAITHFUL_PARAMS, "lbvh", build="karras"),
    ),
    _factor(
        "traversal=ordered",
        "BVH and LBVH ordered traversal (nearer child first, early exit)",
        params=_with(_with(FAITHFUL_PARAMS, "bvh", traversal="ordered"), "lbvh", traversal="ordered"),
    ),
    _factor("shading off", "renders without shading", configs=UNSHADED_CONFIGS),
    _factor(
        "tests counted every time",
        "kd-tree tests counted at every leaf (no mailbox)",
        params=_with(FAITHFUL_PARAMS, "kdtree", mailbox="false"),
    ),
    _factor("models in triangles", "bunny, forest and city sized in triangles", models=OUR_UNIT_MODELS),
    _factor("City BVH depth 50", "Table 5's City median BVH uncapped (depth 50)", model_params=()),
    _factor(
        "lbvh build=median",
        "the LBVH as the median BVH's build after Morton codes and a sort (published code)",
        params=_with(FAITHFUL_PARAMS, "lbvh", build="median"),
        by_construction="lbvh build=median is the median BVH's tree and build after two extra stages",
        evidence=f"{PUBLISHED_CODE} builds the LBVH's children with the median BVH's builder",
    ),
]
SETTING = {s.name: s for s in SETTINGS}
