"""minkq.mpi under mpirun: mpi_ranks.py on 2 and 3 ranks (skipped without mpi4py, mpirun or
libminkq_mpi, with the reason)."""

import os
import random
import shutil
import subprocess
import sys

import pytest

HERE = os.path.dirname(os.path.abspath(__file__))


def _skip_reason():
    try:
        import mpi4py  # noqa: F401
    except ImportError:
        return "mpi4py is not installed"
    if shutil.which("mpirun") is None:
        return "no mpirun"
    import minkq.mpi

    try:
        minkq.mpi._load()
    except ImportError as e:
        return str(e)
    return None


@pytest.mark.parametrize("ranks", [2, 3])
def test_union_over_ranks_is_the_single_process_pair_set(ranks):
    reason = _skip_reason()
    if reason:
        pytest.skip(reason)
    seed = int(os.environ.get("MINKQ_TEST_SEED", random.randrange(2**31)))
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    run = subprocess.run(["mpirun", "-n", str(ranks), sys.executable, os.path.join(HERE, "mpi_ranks.py"), str(seed)],
                         env=env, capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, f"seed {seed}:\n{run.stdout}\n{run.stderr}"
    assert f"{ranks} ranks, seed {seed}, 0 failures" in run.stdout


def test_the_example_runs_on_three_ranks():
    reason = _skip_reason()
    if reason:
        pytest.skip(reason)
    example = os.path.join(HERE, "..", "..", "..", "examples", "python", "distributed.py")
    if not os.path.exists(example):
        pytest.skip("examples/python/distributed.py is not beside these tests (an installed copy)")
    env = dict(os.environ, OMPI_ALLOW_RUN_AS_ROOT="1", OMPI_ALLOW_RUN_AS_ROOT_CONFIRM="1",
               OMPI_MCA_rmaps_base_oversubscribe="1")
    run = subprocess.run(["mpirun", "-n", "3", sys.executable, example, "--size", "40"], env=env,
                         capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, f"{run.stdout}\n{run.stderr}"
    assert "vt: " in run.stdout and "ee: " in run.stdout and "DIFFERENT" not in run.stdout
    # The device helper: this machine's GPUs, or the CPU.
    from mpi4py import MPI

    import minkq.mpi

    assert minkq.mpi.local_device(MPI.COMM_WORLD) in {"cpu"} | {f"cuda:{i}" for i in range(16)}


def test_a_missing_library_is_a_clear_import_error(monkeypatch, tmp_path):
    import minkq.mpi

    monkeypatch.setattr(minkq.mpi, "_lib", None)
    monkeypatch.setenv("MINKQ_MPI_LIB", str(tmp_path / "libminkq_mpi.so"))
    with pytest.raises(ImportError, match="MINKQ_MPI_LIB_DIR"):
        minkq.mpi._load()
