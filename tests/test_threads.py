"""The library's BLAS threads: one thread inside its entry points, the user's settings restored after."""
from __future__ import annotations

import threading

import numpy as np
import pytest

from thetasol import inertia
from thetasol.core import threads
from thetasol.core.threads import blas_threads, single_blas_thread
from thetasol.protocol import Solution

threadpoolctl = pytest.importorskip("threadpoolctl")


def _blas_threads() -> list[int]:
    import scipy.linalg  # noqa: F401  (scipy's own BLAS is counted too)

    return [i["num_threads"] for i in threadpoolctl.threadpool_info() if i["user_api"] == "blas"]


@pytest.fixture
def two_threads():
    """The user's setting: every BLAS on 2 threads (skipped where a BLAS cannot have 2)."""
    import scipy.linalg  # noqa: F401  (loaded first, so that the limit reaches scipy's BLAS too)

    with threadpoolctl.threadpool_limits(limits=2, user_api="blas"):
        if not _blas_threads() or min(_blas_threads()) < 2:
            pytest.skip("this BLAS cannot be set to 2 threads")
        yield


def test_limit_inside_and_restored_after(two_threads):
    with blas_threads():
        assert set(_blas_threads()) == {1}
        with blas_threads():                       # nested: still 1, and the outer exit restores
            assert set(_blas_threads()) == {1}
        assert set(_blas_threads()) == {1}
    assert set(_blas_threads()) == {2}


def test_restored_when_the_call_raises(two_threads):
    @single_blas_thread
    def fails():
        assert set(_blas_threads()) == {1}
        raise ValueError("bad data")

    with pytest.raises(ValueError, match="bad data"):
        fails()
    assert set(_blas_threads()) == {2}


def test_solution_evaluation_runs_on_one_thread(two_threads):
    seen = []

    class Probe(Solution):
        def _evaluate(self, t):
            seen.append(_blas_threads())
            return (t[:, None] * np.ones(3),)

    (x,) = Probe()(np.linspace(0.0, 1.0, 5))
    assert x.shape == (5, 3) and seen == [[1] * len(seen[0])]
    assert set(_blas_threads()) == {2}


def test_one_time_of_a_closed_form_skips_the_guard(two_threads):
    """One time of a closed form runs with the BLAS as the user set it (matrix-vector products only);
    a numerical reference, which integrates up to that time, still gets one thread."""
    seen = []

    class Probe(Solution):
        def _evaluate(self, t):
            seen.append(min(_blas_threads()))
            return (t[:, None] * np.ones(3),)

    class Reference(Probe):
        _AT_ONCE = True

    Probe()(0.5)
    Probe()(np.array([0.5, 1.0]))
    Reference()(0.5)
    assert seen == [2, 1, 1]


def test_one_time_bits_whatever_the_blas_threads(two_threads):
    """Skipping the guard changes no result: the theta-function rotation at one time gives the same bits
    with the BLAS on the user's 2 threads as inside the guard.  (That OpenBLAS runs these matrix-vector
    products on one thread, CPU time equal to wall time, is measured, not asserted: a timing test would
    be flaky on a shared machine.)"""
    from thetasol import solve_rotation

    a = np.array([[0.3, 0.1, -0.2], [0.1, -0.4, 0.05], [-0.2, 0.05, 0.6]])
    sol = solve_rotation(inertia([1.0, 1.7, 2.3]), a, np.eye(3), [0.4, -0.3, 0.8])
    assert sol.method.startswith("theta/")
    w2, Q2 = sol(1e6)
    with blas_threads():
        w1, Q1 = sol(1e6)
    assert np.array_equal(w1, w2) and np.array_equal(Q1, Q2)


def test_solve_rotation_leaves_the_users_setting(two_threads):
    from thetasol import solve_rotation

    sol = solve_rotation(inertia([1.0, 2.0, 3.5]), np.zeros((3, 3)), np.eye(3), [0.1, 1.0, 0.2])
    sol(np.linspace(0.0, 10.0, 7))
    assert set(_blas_threads()) == {2}


def test_limit_none_leaves_the_blas_alone(two_threads, monkeypatch):
    monkeypatch.setattr(threads, "LIMIT", None)
    with blas_threads():
        assert set(_blas_threads()) == {2}


def test_several_python_threads(two_threads):
    """A thread leaving while another is still inside does not restore; the last one out does.

    (Set from the main thread: OpenBLAS ignores a worker thread's setting once the main thread has
    set one, so the limit itself is checked from the main thread.)
    """
    done = []

    def work():
        with blas_threads():
            done.append(True)

    with blas_threads():
        assert set(_blas_threads()) == {1}
        worker = threading.Thread(target=work)
        worker.start()
        worker.join()
        assert done == [True] and set(_blas_threads()) == {1}
    assert set(_blas_threads()) == {2}


def test_scipy_blas_found_once_loaded():
    """The theta-function set-ups of the 13 reference bodies load no scipy module (scipy.linalg costs ~0.1 s
    at a process's first call, scipy.integrate ~0.4 s); a scipy BLAS loaded afterwards is limited from
    the next call on."""
    import pathlib
    import subprocess
    import sys
    refs = pathlib.Path(__file__).parent / "data" / "rotation" / "refs.json"
    code = (
        "import json, sys, numpy as np, thetasol\n"
        "from thetasol.core import threads\n"
        f"for d in json.load(open({str(refs)!r})).values():\n"
        "    thetasol.solve_rotation(thetasol.inertia(d['J']), np.array(d['a']), np.array(d['Q0']), np.array(d['omega0']))\n"
        "loaded = sorted(m for m in sys.modules if m.split('.')[0] == 'scipy')\n"
        "assert not loaded, f'scipy loaded by the set-up: {loaded[:5]}'\n"
        "n0 = len(threads._blas_controllers())\n"
        "import scipy.linalg\n"
        "n1 = len(threads._blas_controllers())\n"
        "import threadpoolctl\n"
        "print(n0, n1, sum(i['user_api'] == 'blas' for i in threadpoolctl.threadpool_info()))\n")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout.split()
    n0, n1, n_all = (int(x) for x in out)
    assert n0 >= 1 and n1 == n_all
