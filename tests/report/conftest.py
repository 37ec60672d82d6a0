"""A small report built once per session (solve, cross-check on Clarabel, simulation)."""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml

SMALL = {
    "lmic": 1,
    "name": "Two-state DT plant & friends <demo>",
    "source": "lmic tests",
    "data": {"A": [[0.9, 0.2], [-0.1, 0.95]], "C": [[1.0, 0.0]]},
    "params": {"beta": 0.001},
    "published": {"L": [[0.5], [0.1]]},
    "simulation": {"nonlinearity": ["0", "0.03*sin(x1)"], "input": "sin(t)", "x0": [1.0, -1.0], "horizon": 20},
}


@pytest.fixture(scope="session")
def small_system(tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("report") / "small.yaml"
    path.write_text(yaml.safe_dump(SMALL))
    return path


@pytest.fixture(scope="session")
def small_report(small_system):
    from lmic.report import build_report

    return build_report("qib.thm1", small_system, crosscheck_backends=["clarabel", "cvxopt"])


@pytest.fixture(scope="session")
def small_report_file(small_report, tmp_path_factory) -> Path:
    path = tmp_path_factory.mktemp("report-out") / "report.html"
    small_report.write(path)
    return path
