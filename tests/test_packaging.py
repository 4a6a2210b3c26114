"""Installed as users install it (a wheel, not editable, not the source tree on sys.path): every package and the
sample .tir files are in the wheel, and the installed `mftyre` finds its bundled files from any folder."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

from conftest import PROJECT


def _run(cmd, **kw):
    out = subprocess.run(cmd, capture_output=True, text=True, timeout=300, **kw)
    assert out.returncode == 0, f"{cmd}:\n{out.stdout}\n{out.stderr}"
    return out


@pytest.fixture(scope="module")
def wheel(tmp_path_factory) -> Path:
    """The wheel, built offline (no build isolation) from a copy of the sources, so no build/ or egg-info is
    left in the working tree."""
    src = tmp_path_factory.mktemp("src")
    for name in ("pyproject.toml", "README.md"):
        shutil.copy2(PROJECT / name, src / name)
    for name in ("mftyre", "swift", "fmu", "tir_files"):
        shutil.copytree(PROJECT / name, src / name, ignore=shutil.ignore_patterns("__pycache__", "*.pyc"))
    dist = tmp_path_factory.mktemp("dist")
    _run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "--no-build-isolation", "--no-index",
          "-q", "-w", str(dist)])
    (whl,) = dist.glob("mftyre-*.whl")
    return whl


def test_wheel_holds_every_package_and_the_sample_files(wheel):
    import mftyre

    assert wheel.name.startswith(f"mftyre-{mftyre.__version__}-")  # one version string (pyproject reads it)
    names = set(zipfile.ZipFile(wheel).namelist())
    packages = {str(p.parent.relative_to(PROJECT)) for top in ("mftyre", "swift", "fmu")
                for p in (PROJECT / top).rglob("__init__.py")}
    for package in packages:  # pyproject lists the packages: a new one must be added there
        assert f"{package}/__init__.py" in names, f"package {package} is not in the wheel (pyproject.toml)"
    for tir in (PROJECT / "tir_files").glob("*.tir"):
        assert f"mftyre/tir_files/{tir.name}" in names
    for source in [*(PROJECT / "fmu" / "native").glob("*.[ch]"), PROJECT / "fmu" / "README.md"]:
        # `mftyre fmu build` compiles the native FMU from these at the user's site (package data of fmu)
        assert f"fmu/{source.relative_to(PROJECT / 'fmu').as_posix()}" in names, f"{source.name} is not in the wheel"


def test_installed_wheel_runs_on_its_bundled_files_from_any_folder(wheel, tmp_path):
    """A fresh venv with the wheel installed without dependencies; they come from this interpreter's
    site-packages, appended to the venv's path by a .pth file (after the venv's own site-packages, and without
    running their .pth files, so an editable install of mftyre there stays out). Commands run from an empty
    folder with no PYTHONPATH."""
    venv = tmp_path / "venv"
    _run([sys.executable, "-m", "venv", "--without-pip", str(venv)])
    python = venv / ("Scripts" if os.name == "nt" else "bin") / "python"
    venv_site = _run([str(python), "-c", "import sysconfig; print(sysconfig.get_paths()['purelib'])"]).stdout.strip()
    outer = [p for p in sys.path if p.rstrip("/\\").endswith("site-packages")]
    Path(venv_site, "outer_dependencies.pth").write_text("\n".join(outer) + "\n")
    _run([sys.executable, "-m", "pip", "--python", str(python), "install", "--no-deps", "--no-index", "-q",
          str(wheel)])
    env = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    work = tmp_path / "work"
    work.mkdir()
    code = ("import mftyre, mftyre.files as f; print(mftyre.__file__); "
            "print(f.sample_tir('car_205_60R15_mf61.tir')); print(f.sample_tir('car_205_60R15_mf62_swift.tir')); "
            "import fmu.native_build as nb; print(nb.__file__); print(nb.C_DIR / 'fmi2_tyre.c')")
    lines = _run([str(python), "-c", code], cwd=work, env=env).stdout.split()
    site = venv.resolve()
    assert all(Path(line).resolve().is_relative_to(site) for line in lines), lines
    sample = lines[1]
    assert Path(lines[4]).is_file()  # the installed fmu package finds its C wrapper (`mftyre fmu build`)
    out = _run([str(python), "-m", "mftyre", "eval", sample, "--alpha", "0deg,4deg", "--outputs", "fy"],
               cwd=work, env=env).stdout
    assert "fy [N]" in out
    assert "--out" in _run([str(python), "-m", "mftyre", "demo", "--help"], cwd=work, env=env).stdout
    script = venv / ("Scripts" if os.name == "nt" else "bin") / "mftyre"
    assert "checked 1 file" in _run([str(script), "check", sample], cwd=work, env=env).stdout
