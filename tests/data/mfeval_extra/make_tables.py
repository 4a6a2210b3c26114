"""Make the MFeval 4.3.1 reference tables of this folder where the shared ones are silent: loads from 0 to
1.5 FZMAX, speeds around VXLOW and far above LONGVL (both ways), pressures beyond PRESMIN..PRESMAX, omega given or
estimated, every use mode (111 ... 222), for every sample file (the MFeval sample files of
../shared/reference/mfeval/ and the repository's tir_files/).

    python tests/data/mfeval_extra/make_tables.py MFEVAL_DIR [--shared DIR] [--octave octave]

MFEVAL_DIR is the unmodified MFeval 4.3.1 distribution (the folder MFeval/ of github.com/nusfsae/NUS_LTS at commit
7c9fd69b8e698ba5a59776d9d29fa97dc128a2d0, holding +mfeval/Solver.m and +mfeval/readTIR.m). It is run by GNU Octave
(7.x) with two shims written to a temporary folder that touch no equation: a no-op ``coder.extrinsic`` and
``contains`` (absent in Octave 7); ``mfeval.m`` itself stays off the path (Octave would mistake
``mfeval.readTIR`` for a call of it): a temporary folder holds a link to ``+mfeval`` only. Each row is one call of
``mfeval.Solver().fullSteadyState(mfeval.readTIR(file), inputs, useMode)`` (run_mfeval.m), so no row depends on
another. MFeval's code is not copied here.

Output per .tir file: ``<stem>.csv.gz``, a header row and one row per call: the inputs ``in_Fz in_kappa in_alpha
in_gamma in_phit in_Vx in_P in_omega``, ``useMode``, ``ncols`` (7: omega estimated by MFeval, 8: omega given), the
MFeval outputs of :data:`mftyre.compat.MFEVAL_COLUMNS` but ``iKya`` (0 for a one-row call), and ``rl_residual``:
MFeval's own MF 6.2 vertical force at the Rl it returned minus Fz (its secant tolerance is 1e-6 FNOMIN; 0 for the
other FITTYPs). Numbers in ``%.17g``: they parse back to the binary64 values MFeval used and returned.
``manifest.json`` records the md5 of every .tir and of Solver.m/readTIR.m and the Octave version.
"""
from __future__ import annotations

import argparse
import gzip
import hashlib
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
REPO = HERE.parents[2]
sys.path.insert(0, str(REPO))
from mftyre.tir import read_tir  # noqa: E402  (the ranges of each file; the oracle reads the file itself)

INPUTS = ("in_Fz", "in_kappa", "in_alpha", "in_gamma", "in_phit", "in_Vx", "in_P", "in_omega")
OUTPUTS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz", "kappa", "alpha", "gamma", "phit", "Vx", "P", "Re", "rho", "2a", "t",
           "mux", "muy", "omega", "Rl", "2b", "Mzr", "Cx", "Cy", "Cz", "Kya", "sigmax", "sigmay", "iKya", "Kxk")
KEPT = tuple(c for c in OUTPUTS if c != "iKya")
MODES = (111, 112, 121, 122, 211, 212, 221, 222)
SHIMS = {"+coder/extrinsic.m": "function extrinsic(varargin)\nend\n",
         "contains.m": "function tf = contains(str, pattern)\n  tf = ~isempty(strfind(str, pattern));\nend\n"}


def sample_files(shared: Path) -> list[Path]:
    return sorted(shared.glob("*.tir")) + sorted((REPO / "tir_files").glob("*.tir"))


def md5(path: Path) -> str:
    return hashlib.md5(path.read_bytes()).hexdigest()


def design(prm, seed: int) -> np.ndarray:
    """Rows [Fz kappa alpha gamma phit Vx P omega useMode ncols]: a load sweep 0..1.5 FZMAX in every mode, then
    random rows drawn from the regions the shared tables leave out."""
    rng = np.random.default_rng(seed)
    fzmax, fzmin, fz0 = prm.FZMAX, prm.FZMIN, prm.FNOMIN
    v0, vlow, r0 = prm.LONGVL, prm.VXLOW, prm.UNLOADED_RADIUS
    pmin, pmax, pnom = prm.PRESMIN, prm.PRESMAX, prm.NOMPRES
    loads = np.array([0.0, 0.5, 0.2 * fzmin, 0.7 * fzmin, fzmin, 0.3 * fzmax, 0.6 * fzmax, 0.95 * fzmax, fzmax,
                      1.0001 * fzmax, 1.02 * fzmax, 1.1 * fzmax, 1.2 * fzmax, 1.35 * fzmax, 1.5 * fzmax])
    loads = np.unique(np.round(loads, 2))
    speeds = np.array([0.3, 0.999, 1.0, 1.001, 2.0]) * vlow
    speeds = np.concatenate([speeds, np.array([0.5, 1.0, 3.0, 6.0, 12.0, 30.0]) * v0, [-0.5 * vlow, -2.0 * v0]])
    pressures = np.array([0.5 * pmin, 0.9 * pmin, pmin, pnom, pmax, 1.1 * pmax, 1.5 * pmax])
    kappas = [0.0, 0.02, -0.02, 0.1, -0.3, -1.0, 0.8, 1.2 * prm.KPUMAX, 1.2 * prm.KPUMIN]
    alphas = [0.0, 0.03, -0.03, 0.15, -0.4, 1.2 * prm.ALPMAX, 1.2 * prm.ALPMIN]
    gammas = [0.0, 0.03, -0.03, 0.1, 1.2 * prm.CAMMAX, 1.2 * prm.CAMMIN]
    rows = []

    def phit_for(mode):
        return 0.0 if mode % 10 == 1 else float(rng.choice([-1, 1]) * 10 ** rng.uniform(-3, 0))

    for mode in MODES:  # the load sweep: free rolling with camber, and combined slip
        for fz in loads:
            for kappa, alpha, gamma in ((0.0, 0.0, 0.03), (0.06, -0.08, -0.02)):
                rows.append([fz, kappa, alpha, gamma, phit_for(mode), v0, pnom, 0.0, mode, 7])
    for _ in range(560):
        mode = int(rng.choice(MODES))
        fz = float(rng.choice(loads)) if rng.random() < 0.6 else float(rng.uniform(0, 1.5 * fzmax))
        kappa = float(rng.choice(kappas)) if rng.random() < 0.5 else float(rng.uniform(-0.3, 0.3))
        alpha = float(rng.choice(alphas)) if rng.random() < 0.5 else float(rng.uniform(-0.2, 0.2))
        gamma = float(rng.choice(gammas)) if rng.random() < 0.5 else float(rng.uniform(-0.08, 0.08))
        vx = float(rng.choice(speeds)) if rng.random() < 0.6 else float(rng.uniform(3.0, 2.5 * v0))
        p = float(rng.choice(pressures)) if rng.random() < 0.5 else float(rng.uniform(0.5 * pmin, 1.5 * pmax))
        given = rng.random() < 0.25 and vx != 0.0
        omega = (1 + kappa) * vx / (0.97 * r0) * rng.uniform(0.95, 1.05) if given else 0.0
        rows.append([fz, kappa, alpha, gamma, phit_for(mode), vx, p, omega, mode, 8 if given else 7])
    table = np.array(rows)
    table[:, 0] = np.round(table[:, 0], 2)
    table[:, 1:5] = np.round(table[:, 1:5], 6)
    table[:, 5] = np.round(table[:, 5], 4)
    table[:, 6] = np.round(table[:, 6])
    table[:, 7] = np.round(table[:, 7], 4)
    table[(table[:, 9] == 8) & (table[:, 7] == 0), 9] = 7  # an omega rounded to 0 means "estimate it"
    return table


def run_octave(octave: str, tir: Path, table: np.ndarray, work: Path) -> np.ndarray:
    infile, outfile = work / "in.csv", work / "out.csv"
    np.savetxt(infile, table, delimiter=",", fmt="%.17g")
    script = (f"addpath('{work / 'shims'}'); addpath('{work / 'pkg'}'); addpath('{HERE}'); "
              f"run_mfeval('{tir}', '{infile}', '{outfile}');")
    subprocess.run([octave, "--no-gui", "--no-window-system", "-q", "--eval", script], check=True,
                   stdout=subprocess.DEVNULL)
    return np.atleast_2d(np.loadtxt(outfile, delimiter=","))


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mfeval_dir", type=Path, help="the MFeval 4.3.1 folder (holding +mfeval/)")
    ap.add_argument("--shared", type=Path, default=REPO.parent / "shared" / "reference" / "mfeval",
                    help="folder of the MFeval sample .tir files")
    ap.add_argument("--octave", default="octave")
    args = ap.parse_args(argv)
    package = (args.mfeval_dir / "+mfeval").resolve()
    if not (package / "Solver.m").is_file():
        ap.error(f"{package / 'Solver.m'} not found: MFEVAL_DIR must hold the +mfeval package")
    version = subprocess.run([args.octave, "--version"], capture_output=True, text=True).stdout.splitlines()[0]
    manifest = {"mfeval": {name: md5(package / name) for name in ("Solver.m", "readTIR.m")}, "octave": version,
                "files": {}}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        for rel, text in SHIMS.items():
            (work / "shims" / rel).parent.mkdir(parents=True, exist_ok=True)
            (work / "shims" / rel).write_text(text)
        (work / "pkg").mkdir()
        os.symlink(package, work / "pkg" / "+mfeval")
        for seed, tir in enumerate(sample_files(args.shared)):
            table = design(read_tir(tir), seed)
            result = run_octave(args.octave, tir, table, work)
            keep = [OUTPUTS.index(c) for c in KEPT] + [len(OUTPUTS)]
            header = ",".join(INPUTS + ("useMode", "ncols") + KEPT + ("rl_residual",))
            lines = [header] + [",".join(f"{int(v)}" if j in (8, 9) else f"{v:.17g}" for j, v in enumerate(row))
                                for row in np.hstack([table, result[:, keep]])]
            target = HERE / f"{tir.stem}.csv.gz"
            with open(target, "wb") as raw, gzip.GzipFile(fileobj=raw, mode="wb", mtime=0) as f:  # same bytes
                f.write(("\n".join(lines) + "\n").encode())
            manifest["files"][tir.name] = {"md5": md5(tir), "table": target.name, "rows": len(table),
                                           "where": "tir_files" if tir.parent == REPO / "tir_files" else "shared"}
            print(f"{tir.name}: {len(table)} rows -> {target.name}")
    (HERE / "manifest.json").write_text(json.dumps(manifest, indent=1) + "\n")


if __name__ == "__main__":
    main()
