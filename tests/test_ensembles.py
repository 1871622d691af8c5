"""solve_many: many bodies or scenes at once, in this process, on a local pool, on a Dask cluster.

The reference is the plain loop: every result must be bit-identical to solving the item alone.
Kept fast: Euler tops (closed forms in elliptic functions, milliseconds), a two-body scene of Euler
tops and, on the Dask cluster, one theta-function body (the rank-one reference body, the cheapest
set-up).
"""
from __future__ import annotations

import concurrent.futures as cf
import json
import pathlib
import sys
import warnings

import numpy as np
import pytest
from conftest import label

from thetasol import inertia
from thetasol.ensembles import solve_many
from thetasol.protocol import ClosedFormUnavailable
from thetasol.scenes.format import load_scene
from thetasol.solutions.rotation.dispatch import solve_rotation

REFS = pathlib.Path(__file__).parent / "data" / "rotation" / "refs.json"
T = np.linspace(0.0, 50.0, 11)


def _euler(w):
    return dict(I=inertia([1.0, 2.0, 3.5]), a=np.zeros((3, 3)), Q0=np.eye(3), omega0=[0.1, 1.0, w])


def _theta():
    d = json.loads(REFS.read_text())["rank_one"]
    return dict(I=inertia(np.diag(d["J"])), a=np.array(d["a"]), Q0=np.array(d["Q0"]), omega0=np.array(d["omega0"]))


BAD = dict(I=[1.0, 2.0, -3.5], a=np.zeros((3, 3)), Q0=np.eye(3), omega0=[0.1, 1.0, 0.2])
#: a potential 1e-13 of the spin: valid data, refused at once (below MIN_POTENTIAL)
NO_CLOSED_FORM = dict(I=inertia([1.0, 2.0, 3.5]), a=1e-13 * np.diag([1.0, 2.0, 3.0]), Q0=np.eye(3), omega0=[0.1, 1.0, 0.2])
#: two bodies in an isotropic potential: the split with Euler tops, milliseconds
SMALL_SCENE = """
name = "pair"
[potential]
a = [[0.5, 0.0, 0.0], [0.0, 0.5, 0.0], [0.0, 0.0, 0.5]]
b = [0.0, 0.0, 0.0]
[[bodies]]
name = "base"
mass = 2.0
box = [1.0, 0.6, 0.3]
[[bodies]]
name = "arm"
mass = 1.0
box = [0.9, 0.2, 0.2]
[[joints]]
parent = "base"
child = "arm"
parent_point = [0.5, 0.0, 0.0]
child_point = "central"
[initial]
q = [0.5, 0.0, 0.0]
v = [0.0, 0.2, 0.0]
[initial.omega]
base = [0.1, 0.4, 0.2]
arm = [0.5, 0.1, -0.3]
[output]
t_end = 2.0
samples = 5
"""


def _same(a, b):
    return all(np.array_equal(x, y) for x, y in zip(a, b, strict=True))


def _identity(x):
    return x


def _warning_solver(x):
    """A solver that warns (module level: picklable for the pools)."""
    warnings.warn(f"lost accuracy {x}", RuntimeWarning, stacklevel=1)
    return x


def test_serial_in_input_order_and_bit_identical():
    items = [_euler(w) for w in (0.2, 0.3, 0.5, 0.7)]
    sols = solve_many(items, workers=1)
    states = solve_many(items, workers=1, t=T, chunksize=3)
    for item, sol, st in zip(items, sols, states, strict=True):
        ref = solve_rotation(**item)(T)
        assert _same(sol(T), ref) and _same(st, ref)


def test_tuples_and_another_solver():
    item = _euler(0.3)
    args = (item["I"], item["a"], item["Q0"], item["omega0"])
    (st,) = solve_many([args], workers=1, t=T)
    assert _same(st, solve_rotation(*args)(T))
    assert solve_many([(1,), {"x": 2}], solver=_identity, workers=1, progress=False) == [1, 2]


def test_errors_return_or_raise():
    assert NotImplementedError in ClosedFormUnavailable.__mro__
    items = [_euler(0.2), BAD, NO_CLOSED_FORM, _euler(0.3)]
    out = solve_many(items, workers=1, errors="return")
    assert isinstance(out[1], ValueError) and "inertia I must be positive definite" in str(out[1])
    assert isinstance(out[2], ClosedFormUnavailable) and "integrate_rotation" in str(out[2])
    assert label(out[0]) == label(out[3]) == "elliptic"
    with pytest.raises(ValueError, match="inertia I must be positive definite") as info:
        solve_many(items, workers=1)
    assert info.value.__notes__ == ["solve_many: item 1 of 4"]
    with pytest.raises(ClosedFormUnavailable) as info:
        solve_many(items[2:], workers=1)
    assert info.value.__notes__ == ["solve_many: item 0 of 2"]


def test_faults_are_raised_in_both_modes():
    def broken(_):
        raise ZeroDivisionError("a bug")

    for mode in ("raise", "return"):
        with pytest.raises(ZeroDivisionError) as info:
            solve_many([(1,), (2,)], solver=broken, workers=1, errors=mode)
        assert info.value.__notes__ == ["solve_many: raised while solving item 0"]


def test_bad_arguments():
    with pytest.raises(ValueError, match="errors must be"):
        solve_many([_euler(0.2)], errors="ignore")
    with pytest.raises(ValueError, match="workers must be"):
        solve_many([_euler(0.2)], workers=0)
    with pytest.raises(TypeError, match="item 1 is a float"):
        solve_many([_euler(0.2), 3.0], workers=1)
    with pytest.raises(TypeError, match="client must be"):
        solve_many([_euler(0.2)], client=object())
    assert solve_many([], workers=1) == []


def test_warnings_come_back_with_the_item():
    with pytest.warns(RuntimeWarning) as record:
        assert solve_many([(3,), (7,)], solver=_warning_solver, workers=1) == [3, 7]
    assert [str(w.message) for w in record] == ["item 0: lost accuracy 3", "item 1: lost accuracy 7"]


def test_progress():
    seen = []
    solve_many([(i,) for i in range(5)], solver=_identity, workers=1, chunksize=2,
               progress=lambda done, total: seen.append((done, total)))
    assert seen == [(2, 5), (4, 5), (5, 5)]


def test_progress_and_dask_name_the_extras_when_absent(monkeypatch):
    monkeypatch.setitem(sys.modules, "tqdm", None)
    monkeypatch.setitem(sys.modules, "tqdm.auto", None)
    monkeypatch.setitem(sys.modules, "distributed", None)
    with pytest.raises(ImportError, match=r"thetasol\[progress\]"):
        solve_many([_euler(0.2)], workers=1, progress=True)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        assert len(solve_many([_euler(0.2)] * 60, workers=1)) == 60   # progress=None: no bar, no noise
    with pytest.raises(ImportError, match=r"thetasol\[dask\]"):
        solve_many([_euler(0.2)], client="dask")


def test_scenes_and_scene_files(tmp_path):
    path = tmp_path / "pair.toml"
    path.write_text(SMALL_SCENE)
    scene = load_scene(path)
    trajs = solve_many([path, scene, str(path)], workers=1, t=scene.t)
    ref = scene.solution().trajectories(scene.t)
    assert "base=elliptic" in scene.solution().diagnostics["parts"]
    for tr in trajs:
        assert np.array_equal(tr.position, ref.position) and np.array_equal(tr.attitude, ref.attitude)


def test_local_process_pool():
    """Two spawned processes: the same bits as the loop; one item refused, returned in place."""
    items = [_euler(0.2), _euler(0.3), _euler(0.5), NO_CLOSED_FORM]
    out = solve_many(items, workers=2, t=T, errors="return")
    assert isinstance(out[3], ClosedFormUnavailable)
    for item, st in zip(items[:3], out[:3], strict=True):
        assert _same(st, solve_rotation(**item)(T))


def test_an_executor_of_your_own():
    with cf.ThreadPoolExecutor(max_workers=2) as pool:
        out = solve_many([_euler(0.2), _euler(0.3)], client=pool, t=T)
        assert pool.submit(int, "4").result() == 4          # left open for the next call
    assert _same(out[1], solve_rotation(**_euler(0.3))(T))


def test_dask_local_cluster():
    distributed = pytest.importorskip("distributed")
    items = [_euler(0.2), _theta(), _euler(0.5), BAD]
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                                  dashboard_address=None) as cluster, distributed.Client(cluster) as client:
        out = solve_many(items, client=client, t=T, errors="return", progress=False)
        with pytest.raises(ValueError, match="inertia I must be positive definite"):
            solve_many([_euler(0.2), BAD], client="dask", progress=False)
    assert isinstance(out[3], ValueError)
    for item, st in zip(items[:3], out[:3], strict=True):
        assert _same(st, solve_rotation(**item)(T))
