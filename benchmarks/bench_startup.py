"""Start-up cost of the command line: CPU seconds (user + system) of a whole process for `import mftyre` and the
`mftyre` commands `--help`, `fit --help`, `check FILE.tir` and `eval FILE.tir` of one point, the best of --repeat
runs, and which of the slow third-party packages each imports.

    python benchmarks/bench_startup.py                    # this tree
    python benchmarks/bench_startup.py --against 6669f8c  # and a git revision beside it, in the same run

Each command runs in a fresh interpreter from the source tree measured (`python -c "from mftyre.cli import main;
..."` with that tree first on sys.path); compiled bytecode is written and a warm-up run precedes the timed ones, as
for an installed package. CPU time, not wall time: a busy shared machine stretches the wall time (waiting for a
core) far more than the CPU time, which it still inflates somewhat; the load average is printed beside the figures.
"""
from __future__ import annotations

import argparse
import os
import platform
import re
import subprocess
import sys
import tarfile
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SAMPLE = "tir_files/car_205_60R15_mf61.tir"
COMMANDS = {"import mftyre": None, "--help": ["--help"], "fit --help": ["fit", "--help"], "check FILE.tir": ["check", SAMPLE],
            "eval FILE.tir (1 point)": ["eval", SAMPLE]}
#: the packages a command should import only when it needs them
HEAVY = ("numpy", "pandas", "scipy", "lmfit", "matplotlib", "casadi", "fmpy", "pythonfmu", "swift", "fmu")


def _environment(tree: Path) -> dict:
    env = {k: v for k, v in os.environ.items() if k not in ("PYTHONDONTWRITEBYTECODE", "PYTHONPATH")}
    env["PYTHONPATH"] = str(tree)
    env["MPLBACKEND"] = "Agg"
    return env


def _script(argv: list[str], report: bool) -> str:
    tail = (f"import sys; print('MODULES', ' '.join(sorted({{m.split('.')[0] for m in sys.modules}} & {set(HEAVY)!r})),"
            " file=sys.stderr)") if report else ""
    return (f"import contextlib, io, sys\nfrom mftyre.cli import main\nwith contextlib.redirect_stdout(io.StringIO()):"
            f"\n    status = main({argv!r})\n{tail}\nsys.exit(status)")


def run_once(tree: Path, argv: list[str] | None, *, report: bool = False) -> tuple[float, str]:
    """CPU seconds of one process running `mftyre ARGV` from ``tree`` (None: `import mftyre` alone); with ``report``
    also its heavy imports."""
    before = os.times()
    code = _script(argv, report) if argv is not None else (
        "import sys, mftyre\n" + ("print('MODULES', ' '.join(sorted({m.split('.')[0] for m in sys.modules} & "
                                  f"{set(HEAVY)!r})), file=sys.stderr)" if report else ""))
    done = subprocess.run([sys.executable, "-c", code], cwd=tree, env=_environment(tree),
                          stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    after = os.times()
    if done.returncode != 0:
        raise SystemExit(f"mftyre {' '.join(argv)} in {tree} failed ({done.returncode}):\n{done.stderr}")
    modules = re.search(r"^MODULES ?(.*)$", done.stderr, re.M)
    return ((after.children_user - before.children_user) + (after.children_system - before.children_system),
            modules.group(1) if modules else "")


def best(tree: Path, argv: list[str] | None, repeat: int) -> float:
    return min(run_once(tree, argv)[0] for _ in range(repeat))


def import_costs(tree: Path, repeat: int) -> dict[str, float]:
    """CPU seconds that `import X` adds to a bare interpreter (best of ``repeat``), for the slow imports."""
    def cpu(code):
        times = []
        for _ in range(repeat):
            before = os.times()
            subprocess.run([sys.executable, "-c", code], cwd=tree, env=_environment(tree), check=True)
            after = os.times()
            times.append(after.children_user - before.children_user + after.children_system - before.children_system)
        return min(times)

    bare = cpu("pass")
    names = ("numpy", "pandas", "scipy.stats", "scipy.optimize", "lmfit", "matplotlib.figure", "casadi")
    return {name: cpu(f"import {name}") - bare for name in names} | {"(bare interpreter)": bare}


def checkout(revision: str, into: Path) -> Path:
    """The source tree of ``revision`` (git archive) unpacked in ``into``."""
    archive = into / "tree.tar"
    with open(archive, "wb") as f:
        subprocess.run(["git", "archive", revision], cwd=ROOT, stdout=f, check=True)
    with tarfile.open(archive) as tar:
        tar.extractall(into / "tree", filter="data")
    return into / "tree"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--against", metavar="REV", help="also measure this git revision (e.g. the start of a change)")
    parser.add_argument("--repeat", type=int, default=5, help="timed runs per command (best kept; default 5)")
    args = parser.parse_args()
    print(f"# {platform.node()}: {platform.processor() or platform.machine()}, {os.cpu_count()} cores, "
          f"Python {platform.python_version()}; load average before: {os.getloadavg()[0]:.1f}")
    with tempfile.TemporaryDirectory() as tmp:
        trees = {"this tree": ROOT}
        if args.against:
            trees = {f"{args.against}": checkout(args.against, Path(tmp))} | trees
        for tree in trees.values():  # warm-up: bytecode written, files in the page cache
            for argv in COMMANDS.values():
                run_once(tree, argv)
        header = (f"| command | {' | '.join(f'CPU s, {name}' for name in trees)} | "
                  f"{' | '.join(f'heavy imports, {name}' for name in trees)} |")
        print("\n" + header + "\n|" + "---|" * (2 * len(trees) + 1))
        for label, argv in COMMANDS.items():  # side by side: each command measured on every tree in turn
            times = [best(tree, argv, args.repeat) for tree in trees.values()]
            modules = [run_once(tree, argv, report=True)[1] or "none" for tree in trees.values()]
            print(f"| `{label if argv is None else 'mftyre ' + label}` | {' | '.join(f'{t:.2f}' for t in times)} | {' | '.join(modules)} |")
        print(f"\nslow imports (CPU s added to a bare interpreter, best of {args.repeat}):")
        for name, seconds in import_costs(ROOT, args.repeat).items():
            print(f"  {name:20s} {seconds:.2f}")
    print(f"# load average after: {os.getloadavg()[0]:.1f}")


if __name__ == "__main__":
    main()
