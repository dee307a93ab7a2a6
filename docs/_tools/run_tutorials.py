"""Runs the tutorials' code: every docs/tutorials/*.py (not the _helpers) as a script, with the
interpreter running this one and `-W error::DeprecationWarning` (a spelling minkq has deprecated
fails the tutorial, so the pages never teach one), and fails if one exits non-zero.

    python run_tutorials.py TUTORIALS_DIR

A tutorial names what it needs in a line `# needs: NAME ...`: a Python module (warp, torch,
mpi4py), or `cuda` (a GPU that minkq can use). Where one is missing the tutorial is skipped
and the reason printed; a tutorial whose GPU part alone needs a GPU runs its CPU part and says
itself what it skipped.
"""
import importlib.util
import re
import subprocess
import sys
import time
from pathlib import Path


def missing(need: str):
    if need == "cuda":
        import minkq

        return None if minkq.cuda_device_count() > 0 else "no CUDA GPU (minkq.cuda_device_count() == 0)"
    return None if importlib.util.find_spec(need) else f"no module {need!r} in {sys.executable}"


def main(folder: Path) -> int:
    failed, skipped, ran = [], [], 0
    for script in sorted(folder.glob("[!_]*.py")):
        needs = re.search(r"^# needs: (.+)$", script.read_text(), re.M)
        reasons = [m for m in (missing(n) for n in (needs.group(1).split() if needs else [])) if m]
        if reasons:
            skipped.append(script.name)
            print(f"tutorial {script.name}: SKIPPED: {'; '.join(reasons)}")
            continue
        started = time.monotonic()
        run = subprocess.run([sys.executable, "-W", "error::DeprecationWarning", script.name], cwd=folder, capture_output=True, text=True, timeout=600)
        ran += 1
        status = "ok" if run.returncode == 0 else f"FAILED (exit {run.returncode})"
        print(f"tutorial {script.name}: {status} ({time.monotonic() - started:.1f} s)")
        print("    " + (run.stdout + run.stderr).strip().replace("\n", "\n    "))
        if run.returncode != 0:
            failed.append(script.name)
    print(f"tutorials: {ran} ran, {len(skipped)} skipped, {len(failed)} failed {failed if failed else ''}")
    return 1 if failed or not ran else 0


if __name__ == "__main__":
    sys.exit(main(Path(sys.argv[1])))
