"""The scaling fit and figure, and the cost-image figure, on synthetic data with known
answers."""

from __future__ import annotations

import numpy as np
import pytest
from PIL import Image
from synthetic import BVH, EMBREE, KD, SAH, row, write_csv

from accelbench_analysis.cli import main
from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.figures.scaling import cost_figure, fit_slopes, read_cost_csv, scaling_frame

SIZES = {
    "stanford-dragon@decimate=10000": 10000,
    "stanford-dragon@decimate=100000": 100000,
    "stanford-dragon": 871414,
    "stanford-bunny": 69451,
    "stanford-bunny@subdivide=1": 277804,
}
# Known exponents: time = c * triangles^slope.
SLOPES = {"bvh-median": (1.2, 0.3), "bvh-sah": (1.1, 0.25), "kdtree": (1.3, 0.2), "embree": (1.0, 0.15)}
ACCELS = {
    "bvh-median": ("bvh", BVH),
    "bvh-sah": ("bvh", SAH),
    "kdtree": ("kdtree", KD),
    "embree": ("embree", EMBREE),
}


def scaling_rows(failing: str | None = None) -> list[dict]:
    rows = []
    for model, tris in SIZES.items():
        for key, (accel, params) in ACCELS.items():
            b, r = SLOPES[key]
            status = "timeout" if model == failing and key == "kdtree" else "ok"
            x = row(
                model,
                accel,
                params,
                build=2e-7 * tris**b,
                render=0.01 * tris**r,
                config="scaling",
                status=status,
            )
            x["triangles"] = tris
            rows.append(x)
    return rows


@pytest.fixture
def scaling_csv(tmp_path):
    return write_csv(tmp_path / "scaling.csv", scaling_rows(failing="stanford-dragon"))


def test_fit_recovers_the_exponents(scaling_csv):
    frame = scaling_frame(load_results([scaling_csv]))
    assert set(frame["family"]) == {"stanford-dragon", "stanford-bunny"}
    assert set(frame["structure"]) == {"BVH (median)", "BVH (binned SAH)", "kd-tree", "Embree"}
    slopes = fit_slopes(frame).set_index(["family", "structure", "time"])
    for key, label in (
        ("bvh-median", "BVH (median)"),
        ("bvh-sah", "BVH (binned SAH)"),
        ("kdtree", "kd-tree"),
        ("embree", "Embree"),
    ):
        b, r = SLOPES[key]
        for fam in ("stanford-dragon", "stanford-bunny"):
            assert slopes.loc[(fam, label, "build"), "slope"] == pytest.approx(b, rel=1e-3)
            assert slopes.loc[(fam, label, "render"), "slope"] == pytest.approx(r, rel=1e-3)
    # The timed-out full dragon is not a point: the kd-tree's dragon fit has two sizes.
    assert slopes.loc[("stanford-dragon", "kd-tree", "build"), "n"] == 2
    assert slopes.loc[("stanford-dragon", "Embree", "build"), "n"] == 3


def test_one_size_gives_no_fit(tmp_path):
    rows = [r for r in scaling_rows() if r["model"] in ("stanford-dragon", "stanford-bunny")]
    path = write_csv(tmp_path / "one.csv", rows)
    assert fit_slopes(scaling_frame(load_results([path]))).empty
    assert main(["scaling", str(path), "--out", str(tmp_path / "out")]) == 2


def test_scaling_command_writes_figure_and_table(scaling_csv, tmp_path):
    out = tmp_path / "out"
    assert main(["scaling", str(scaling_csv), "--out", str(out)]) == 0
    table = (out / "tables" / "scaling.md").read_text()
    assert "| BVH (median) | 1.20 | 0.30 | 1.20 | 0.30 |" in table
    assert "build slope, stanford-bunny" in table
    with Image.open(out / "figures" / "scaling.png") as im:
        assert im.size[0] > 1000


def test_the_fit_takes_one_row_per_size_of_the_reports_workload(tmp_path, capsys):
    rows = scaling_rows()
    # The same structure on one size on 4 threads (a faster render): left out, said.
    extra = row("stanford-bunny", "bvh", BVH, build=1.0, render=1e-6, config="scaling", render_threads="4")
    extra["triangles"] = SIZES["stanford-bunny"]
    path = write_csv(tmp_path / "s.csv", rows + [extra])
    out = tmp_path / "out"
    assert main(["scaling", str(path), "--out", str(out)]) == 0
    assert "| BVH (median) | 1.20 | 0.30 | 1.20 | 0.30 |" in (out / "tables" / "scaling.md").read_text()
    assert "left out of the scaling fit: 1 rows rendered on more than one thread" in capsys.readouterr().err
    # Two rows of one structure on one size (other parameters): refused, naming them.
    other = row("stanford-bunny", "bvh", dict(BVH, max_prims="4"), build=1.0, render=1.0, config="scaling")
    other["triangles"] = SIZES["stanford-bunny"]
    path = write_csv(tmp_path / "d.csv", rows + [other])
    assert main(["scaling", str(path), "--out", str(out)]) == 2
    assert "more than one row of a structure on one model size" in capsys.readouterr().err


def write_cost(path, w, h, nodes, prims):
    with path.open("w") as fh:
        fh.write("x,y,node_visits,prim_tests\n")
        for y in range(h):
            for x in range(w):
                fh.write(f"{x},{y},{nodes(x, y)},{prims(x, y)}\n")
    return path


def test_read_cost_csv_places_pixels(tmp_path):
    p = write_cost(tmp_path / "a-cost.csv", 4, 3, lambda x, y: 10 * y + x, lambda x, y: 7)
    d = read_cost_csv(p)
    assert d["node_visits"].shape == (3, 4)
    assert d["node_visits"][2, 3] == 23
    assert d["prim_tests"].mean() == 7
    bad = tmp_path / "bad.csv"
    bad.write_text("x,y,node_visits\n0,0,1\n")
    with pytest.raises(ValueError, match="prim_tests"):
        read_cost_csv(bad)


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda t: t[:-4], r"line 13 \(the last row\) has no line break at its end"),
        (lambda t: t.replace("\n2,1,", "\n2,1,nan,", 1), r"line 8 \(row 7\): 5 fields but the header has 4"),
        (
            lambda t: t.replace("\n2,1,12,", "\n2,1,inf,", 1),
            r"column 'node_visits' has values that are not finite on line 8 \(row 7\)",
        ),
        (
            lambda t: t.replace("\n2,1,12,", "\n2,1,-12,", 1),
            r"column 'node_visits' has negative values on line 8 \(row 7\)",
        ),
        (
            lambda t: t.replace("\n2,1,12,", "\n2,1,twelve,", 1),
            r"column 'node_visits' has non-numeric values on line 8 \(row 7\)",
        ),
        (
            lambda t: t.replace("\n2,1,", "\n2.5,1,", 1),
            r"column 'x' has values that are not pixel coordinates on line 8 \(row 7\)",
        ),
        (lambda t: t.replace("\n2,1,", "\n1,1,", 1), r"pixel \(1, 1\) a second time on line 8 \(row 7\)"),
    ],
)
def test_read_cost_csv_refuses_broken_files(tmp_path, edit, message):
    p = write_cost(tmp_path / "a-cost.csv", 4, 3, lambda x, y: 10 * y + x, lambda x, y: 7)
    p.write_text(edit(p.read_text()))
    with pytest.raises(ValueError, match=message):
        read_cost_csv(p)


def test_cost_images_command(tmp_path):
    w, h = 40, 30
    a = write_cost(tmp_path / "bunny-bvh-cost.csv", w, h, lambda x, y: x, lambda x, y: 2)
    b = write_cost(tmp_path / "bunny-kdtree-cost.csv", w, h, lambda x, y: 2 * x, lambda x, y: 3)
    shaded = tmp_path / "shaded.png"
    Image.fromarray(np.full((h, w, 3), 128, dtype=np.uint8)).save(shaded)
    out = tmp_path / "out"
    assert (
        main(
            [
                "cost-images",
                "--model",
                "stanford-bunny",
                "--shaded",
                str(shaded),
                "--cost",
                f"BVH={a}",
                "--cost",
                f"kd-tree={b}",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    with Image.open(out / "figures" / "cost-stanford-bunny.png") as im:
        assert im.size[0] > im.size[1]
    # Different image sizes cannot share panels.
    c = write_cost(tmp_path / "small-cost.csv", 4, 3, lambda x, y: 1, lambda x, y: 1)
    with pytest.raises(ValueError, match="differ in size"):
        cost_figure("m", None, {"a": a, "c": c}, out / "x.png")
    assert main(["cost-images", "--model", "m", "--cost", "no-equals-sign", "--out", str(out)]) == 2
