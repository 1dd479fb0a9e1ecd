"""The grid search's heatmap markers: where a published default setting sits on an axis,
and which settings the report and pbrt publish."""

from __future__ import annotations

import math

import pytest

from accelbench_analysis.grid.heatmaps import marker_position, published_settings


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
