from pathlib import Path

import pytest
from synthetic import realistic_rows, write_csv

from accelbench_analysis.inputs.load import load_results
from accelbench_analysis.inputs.report_numbers import load_report_numbers


@pytest.fixture(scope="session")
def report_nums():
    return load_report_numbers()


@pytest.fixture(scope="session")
def realistic_csv(tmp_path_factory) -> Path:
    return write_csv(tmp_path_factory.mktemp("realistic") / "run.csv", realistic_rows(), with_errors=True)


@pytest.fixture(scope="session")
def realistic(realistic_csv):
    return load_results([realistic_csv])


@pytest.fixture(scope="session")
def analysed_run(realistic_csv, tmp_path_factory) -> Path:
    """A main-job run directory as `make reproduce-tables` leaves it, on synthetic rows:
    csv/ with every kind of run (the report's tables, ray sets, thread scaling, scaling),
    run.json, cost images, then `scaling` and `all` (REPORT.md, tables/, figures/, index.html)."""
    import json
    import shutil

    import numpy as np
    from PIL import Image
    from test_scaling import scaling_rows, write_cost
    from test_workloads import ray_set_csv, thread_csv

    from accelbench_analysis.cli import main

    run = tmp_path_factory.mktemp("results") / "runs" / "20240101T000000Z-0123456"
    csvs = run / "csv"
    csvs.mkdir(parents=True)
    shutil.copyfile(realistic_csv, csvs / "table4.csv")
    ray_set_csv(csvs / "ray-sets.csv")
    thread_csv(csvs / "thread-scaling.csv")
    write_csv(csvs / "scaling.csv", scaling_rows())
    (run / "run.json").write_text(
        json.dumps(
            {
                "job": {
                    "configs": ["table4.yaml", "ray-sets.yaml", "thread-scaling.yaml", "scaling.yaml"],
                    "tag": "",
                },
                "provenance": {"git_sha": "0123456789abcdef0123456789abcdef01234567", "git_dirty": "false"},
                "started": "2024-01-01T00:00:00Z",
                "complete": True,
            }
        )
    )
    costs = run / "cost"
    costs.mkdir()
    a = write_cost(costs / "bvh-cost.csv", 32, 24, lambda x, y: x + y, lambda x, y: 2)
    b = write_cost(costs / "kd-cost.csv", 32, 24, lambda x, y: 2 * x, lambda x, y: 1 + y % 3)
    shaded = costs / "shaded.png"
    Image.fromarray(np.full((24, 32, 3), 140, dtype=np.uint8)).save(shaded)
    cost = ["cost-images", "--model", "stanford-bunny", "--shaded", str(shaded)]
    assert main([*cost, "--cost", f"BVH={a}", "--cost", f"kd-tree={b}", "--out", str(run)]) == 0
    assert main(["scaling", str(csvs / "scaling.csv"), "--out", str(run)]) == 0
    tables = [str(csvs / f) for f in ("table4.csv", "ray-sets.csv", "thread-scaling.csv")]
    assert main(["all", *tables, "--run-csv", str(csvs / "scaling.csv"), "--out", str(run)]) == 0
    return run
