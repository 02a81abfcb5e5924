"""Packaging: a non-editable wheel carries the data and works from any directory."""

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

pytestmark = pytest.mark.slow  # the second tier (tests/conftest.py)

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory):
    pytest.importorskip("hatchling")
    out = tmp_path_factory.mktemp("wheel")
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "wheel",
            "--no-deps",
            "--no-build-isolation",
            "-q",
            "-w",
            str(out),
            str(REPO),
        ],
        check=True,
        capture_output=True,
    )
    (path,) = out.glob("tribojax-*.whl")
    return path


def test_wheel_contains_package_data_and_typing(wheel):
    names = set(zipfile.ZipFile(wheel).namelist())
    assert "tribojax/py.typed" in names
    assert "tribojax/_data/wang2022/table3_contact.csv" in names
    assert "tribojax/_data/README.md" in names


def test_installed_wheel_finds_its_data_from_another_directory(wheel, tmp_path):
    target = tmp_path / "site"
    subprocess.run(
        [
            sys.executable,
            "-m",
            "pip",
            "install",
            "--no-deps",
            "-q",
            "--target",
            str(target),
            str(wheel),
        ],
        check=True,
        capture_output=True,
    )
    code = (
        "import tribojax as tj, tribojax._tables as d\n"
        "print(tj.__file__)\n"
        "print(d.data_dir())\n"
        "print(tj.wang2022_table(3)['load_N'][0])\n"
    )
    env = {**os.environ, "PYTHONPATH": str(target)}
    run = subprocess.run(
        [sys.executable, "-c", code], cwd=tmp_path, env=env, capture_output=True, text=True
    )
    assert run.returncode == 0, run.stderr
    module_file, data, first_load = run.stdout.split()
    assert Path(module_file).is_relative_to(target)
    assert Path(data) == target / "tribojax" / "_data"
    assert float(first_load) == 3.6912
