"""Figure functions write real, non-empty PNGs from a realistic synthetic run, and say why
when they cannot."""

import matplotlib.image as mpimg
import pandas as pd
import pytest
from synthetic import BVH, row, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.outputs.figures import figures

PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


@pytest.fixture(scope="module")
def drawn(realistic, report_nums, tmp_path_factory):
    return figures.write_figures(realistic, report_nums, tmp_path_factory.mktemp("figures"))


@pytest.mark.parametrize("name", list(figures.FIGURES))
def test_figure_is_a_non_empty_png(drawn, name):
    path = drawn[name]
    assert not isinstance(path, figures.Skipped), path
    assert path.read_bytes()[:8] == PNG_MAGIC
    img = mpimg.imread(path)
    assert img.shape[0] > 300 and img.shape[1] > 300
    # Not a blank canvas.
    assert img[..., :3].std() > 0.05


def test_error_figure_skips_without_error_columns(tmp_path, report_nums):
    res = load_results([write_csv(tmp_path / "e.csv", [row("igea", "bvh", BVH, build=1, render=1)])])
    out = figures.error_pareto(res, tmp_path / "e.png")
    assert isinstance(out, figures.Skipped) and "false_misses" in out.reason
    assert not (tmp_path / "e.png").exists()


def test_pareto_front():
    pts = pd.DataFrame({"t": [1.0, 2.0, 3.0, 4.0, 2.5], "err": [5, 3, 4, 0, 3]})
    front = figures.pareto_front(pts, "t", "err")
    assert list(front["t"]) == [1.0, 2.0, 4.0]


def test_sweep_frame_is_relative_to_first_setting(realistic, report_nums):
    df, sweeps = figures.sweep_frame(realistic, report_nums)
    first = df.sort_values("x").groupby(["sweep", "metric", "source"]).first()
    assert (first["relative"] == 1.0).all()
    assert set(df["source"]) == {"ours", "report"}
    assert sweeps["max_prims"].startswith("maxPrims sweep (max_depth=auto")
