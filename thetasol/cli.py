"""Command line: ``python -m thetasol demo``, ``python -m thetasol solve SCENE.toml`` and
``python -m thetasol reference {list, export}``.

``demo`` and ``solve`` print the report of :func:`thetasol.scenes.report.run` (effective bodies, the model of each
part, the exact parts against the numerical references with deviations and timings).
``solve`` (and ``demo`` with ``-o``) also writes the trajectories (``.npz`` or ``.csv``)
and the report (``<stem>.report.txt``), atomically; with ``--plot FILE`` (``.png``, ``.pdf`` or ``.svg``;
needs matplotlib, the ``plot`` extra) a figure of the trajectories (:func:`thetasol.plot.trajectories`).
While they work they show which part is running on stderr (a tqdm bar on a terminal when tqdm is
installed, else a line per part).

``reference list`` prints the exact reference cases of :mod:`thetasol.reference`;
``reference export NAME -o FILE [--t0 T0 --t1 T1 --n N]`` writes one case's exact states on ``N``
equally spaced times to ``.csv`` or ``.json`` (default: the case's own interval, 101 times).

``--t-end T`` and ``--samples N`` replace the scene's output times by ``N`` equally spaced times on
``[0, T]``; ``--no-check`` skips every numerical reference (the closed forms evaluate at any time,
so a far horizon then finishes at once).  A reference expected to take long is announced with its
expected duration and shows its progress on stderr.

Exit status: 0 when no check failed (an inconclusive check, whose reference cannot judge, is
not a failure), 1 when a check failed, 2 on bad input (the message starts with
``thetasol: error:``; nothing is written), 130 on Ctrl-C (the message says which files, each
complete, were written before it; the others are not).
"""
from __future__ import annotations

import argparse
import os
import sys
import time

from thetasol._version import __version__


def _parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(
        prog="python -m thetasol",
        description="Exact solutions of C^k-central configurations of rigid bodies in quadratic potentials "
                    "(Bogoyavlenskij 1992).")
    p.add_argument("--version", action="version", version=f"thetasol {__version__}")
    sub = p.add_subparsers(dest="command", required=True)
    d = sub.add_parser("demo", help="run the bundled space-station scene and compare with numerical references")
    s = sub.add_parser("solve", help="solve a scene file (TOML; see docs/scene_format.md)")
    s.add_argument("scene", help="scene file (.toml)")
    r = sub.add_parser("reference", help="exact reference cases for testing integrators (docs/reference_cases.md)")
    rsub = r.add_subparsers(dest="action", required=True)
    rsub.add_parser("list", help="list the cases")
    e = rsub.add_parser("export", help="write a case's exact states to .csv or .json")
    e.add_argument("name", help="case name (see 'reference list')")
    e.add_argument("-o", "--output", required=True, help="output file (.csv or .json)")
    e.add_argument("--t0", type=float, help="first time (default: the case's own)")
    e.add_argument("--t1", type=float, help="last time (default: the case's own)")
    e.add_argument("--n", type=int, default=101, help="number of equally spaced times (default 101)")
    for q in (d, s):
        q.add_argument("-o", "--output", help="write the trajectories to this .npz or .csv file "
                                              "(and the report to <stem>.report.txt)")
        q.add_argument("--no-check", action="store_true",
                       help="skip every numerical reference (the exact parts are evaluated, not compared)")
        q.add_argument("--t-end", type=float, metavar="T",
                       help="last output time (instead of the scene's; the number of times is kept)")
        q.add_argument("--samples", type=int, metavar="N",
                       help="number of equally spaced output times on [0, t_end] (instead of the scene's)")
        q.add_argument("--plot", metavar="FILE", help="write a figure of the trajectories (.png, .pdf or .svg; "
                                                      "needs matplotlib: pip install \"thetasol[plot]\")")
    return p


def _check_output(path: str) -> None:
    """Refuse an output path that cannot be written, before the (long) solve."""
    if not path.lower().endswith((".npz", ".csv")):
        raise ValueError(f"output file must end in .npz or .csv, got {path!r}")
    _check_folder(path)


def _check_folder(path: str) -> None:
    folder = os.path.dirname(os.path.abspath(path))
    if not os.path.isdir(folder):
        raise ValueError(f"output directory {folder!r} does not exist (for {path!r})")
    if not os.access(folder, os.W_OK):
        raise ValueError(f"output directory {folder!r} is not writable (for {path!r})")


def main(argv: list[str] | None = None) -> int:
    """Entry point; returns the exit status."""
    args = _parser().parse_args(argv)
    if args.command == "reference":
        return _reference(args)
    from thetasol.mechanics.trajectories import write_trajectories
    from thetasol.scenes.format import demo_scene_path, load_scene, with_times
    from thetasol.scenes.report import run

    written = []
    try:
        if args.output is not None:
            _check_output(args.output)
        if args.plot is not None:
            _check_plot(args.plot)
        path = demo_scene_path() if args.command == "demo" else args.scene
        scene = with_times(load_scene(path), args.t_end, args.samples)
        with _Progress() as progress:
            traj, report, checks = run(scene, check=not args.no_check, out=sys.stdout, progress=progress,
                                       references=not args.no_check)
        if args.output is not None:
            for p in write_trajectories(traj, args.output, report=report):
                written.append(p)
                print(f"wrote {p}")
        if args.plot is not None:
            written.append(_write_plot(traj, args.plot))
            print(f"wrote {written[-1]}")
        if args.command == "demo" and args.output is None:
            print(_OUTPUT_HINT + ("; '--plot station.png' draws them" if args.plot is None else ""))
    except ValueError as exc:
        print(f"thetasol: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # the files are written whole or not at all (atomically): the ones listed are complete
        done = f"; written before it: {', '.join(map(str, written))}" if written else "; no file was written"
        print(f"\nthetasol: interrupted{done}", file=sys.stderr)
        return 130
    return 0 if all(c.ok for c in checks) else 1


_OUTPUT_HINT = ("the trajectories were not written: 'python -m thetasol demo -o station.npz' (or .csv) writes "
                "them and this report (station.report.txt)")
_PLOT_SUFFIXES = (".png", ".pdf", ".svg")


def _check_plot(path: str) -> None:
    """Refuse a plot file that cannot be written, or matplotlib missing, before the (long) solve."""
    if not path.lower().endswith(_PLOT_SUFFIXES):
        raise ValueError(f"plot file must end in {', '.join(_PLOT_SUFFIXES)}, got {path!r}")
    _check_folder(path)
    try:
        import thetasol.plot  # noqa: F401
    except ImportError as exc:
        raise ValueError(f"--plot: {exc}") from None


def _write_plot(traj, path: str) -> str:
    """Draw the trajectories (thetasol.plot.trajectories) into ``path``; no pyplot state is touched."""
    from matplotlib.figure import Figure

    from thetasol.plot import trajectories

    fig = trajectories(traj, fig=Figure(figsize=(11, 8), dpi=100))
    fig.savefig(path)
    return path


class _Progress:
    """``run``'s progress on stderr: a tqdm bar on a terminal when tqdm is installed, else a line per part."""

    def __enter__(self):
        self.bar = None
        self.start = time.perf_counter()
        if sys.stderr.isatty():
            try:
                from tqdm import tqdm
            except ImportError:
                pass
            else:
                self.bar = tqdm(total=1, unit="part", file=sys.stderr, leave=False)
        return self

    def __call__(self, label: str, k: int, n: int) -> None:
        if self.bar is not None:
            self.bar.total = n
            self.bar.n = k
            self.bar.set_description(label)
            self.bar.refresh()
        elif label == "done":
            print(f"thetasol: done in {time.perf_counter() - self.start:.1f} s", file=sys.stderr, flush=True)
        else:
            print(f"thetasol: [{k + 1}/{n}] {label} ...", file=sys.stderr, flush=True)

    def __exit__(self, *exc) -> None:
        if self.bar is not None:
            self.bar.close()


def _reference(args) -> int:
    """``reference list`` / ``reference export``; the catalogue is imported only here."""
    import numpy as np

    from thetasol.reference import case, cases

    try:
        if args.action == "list":
            for c in cases():
                print(f"{c.name:<26s} {c.model:<38s} t in [{c.t_span[0]:g}, {c.t_span[1]:g}], {c.y0.size} components")
            return 0
        if not args.output.lower().endswith((".csv", ".json")):
            raise ValueError(f"output file must end in .csv or .json, got {args.output!r}")
        if args.n < 1:
            raise ValueError(f"--n must be at least 1, got {args.n}")
        try:
            c = case(args.name)
        except KeyError as exc:
            raise ValueError(exc.args[0]) from None
        t0 = c.t_span[0] if args.t0 is None else args.t0
        t1 = c.t_span[1] if args.t1 is None else args.t1
        if not (np.isfinite(t0) and np.isfinite(t1)):
            raise ValueError(f"times must be finite, got t0={t0}, t1={t1}")
        print(f"wrote {c.export(args.output, np.linspace(t0, t1, args.n))}")
    except ValueError as exc:
        print(f"thetasol: error: {exc}", file=sys.stderr)
        return 2
    return 0
