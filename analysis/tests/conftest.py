from pathlib import Path

import pytest
from synthetic import realistic_rows, write_csv

from accelbench_analysis.inputs.report_numbers import load_report_numbers
from accelbench_analysis.inputs.schema import load_results


@pytest.fixture(scope="session")
def report_nums():
    return load_report_numbers()


@pytest.fixture(scope="session")
def realistic_csv(tmp_path_factory) -> Path:
    return write_csv(tmp_path_factory.mktemp("realistic") / "run.csv", realistic_rows(), with_errors=True)


@pytest.fixture(scope="session")
def realistic(realistic_csv):
    return load_results([realistic_csv])
