"""Scene reports: a measured deviation against a stated tolerance, and the text being written."""
from __future__ import annotations

import io
from dataclasses import dataclass
from typing import TextIO

__all__ = ["Check", "ReportText", "verdict"]


@dataclass
class Check:
    """One comparison of the report: a max deviation against a stated tolerance.

    With ``reference_error`` (the reference's own error estimate over the checked times) the
    verdict says which side is off: a deviation within the tolerance is ``"ok"``; beyond it by more
    than the reference's error, the checked part is off (``"FAILED"``); beyond it by less, the
    reference cannot tell (``"inconclusive"``: not a failure, and the line says why).
    """

    what: str
    deviation: float
    tolerance: float
    seconds: str
    #: the effective body of a rotation against its reference, and that reference's seconds
    body: str = ""
    reference_seconds: float | None = None
    #: the reference's own error estimate over the checked times (None: taken as exact)
    reference_error: float | None = None
    #: why fewer times than the scene's were checked, or ""
    note: str = ""

    @property
    def status(self) -> str:
        """``"ok"``, ``"inconclusive"`` or ``"FAILED"`` (see the class docstring)."""
        if self.deviation <= self.tolerance:
            return "ok"
        if self.reference_error is not None and self.deviation - self.reference_error <= self.tolerance:
            return "inconclusive"
        return "FAILED"

    @property
    def ok(self) -> bool:
        """Nothing shows the checked part wrong: the check passed or was inconclusive."""
        return self.status != "FAILED"

    def line(self) -> str:
        """The report line of this check (and a second line saying which side is off when it did not pass)."""
        err = "" if self.reference_error is None else f"; reference's own error {self.reference_error:.1e}"
        text = (f"  {self.what}: {self.deviation:.2e} (tolerance {self.tolerance:.1e}{err}) [{self.seconds}]  "
                f"{self.status}")
        if self.status == "inconclusive":
            text += (f"\n    the difference is within the reference's own error estimate {self.reference_error:.1e}: "
                     "the reference is not accurate enough over this horizon to judge the closed form")
        elif self.status == "FAILED" and self.reference_error is not None:
            text += (f"\n    the checked part is off by at least {self.deviation - self.reference_error:.1e} "
                     f"(the difference less the reference's own error estimate {self.reference_error:.1e})")
        if self.note:
            text += f"\n    ({self.note})"
        return text


def verdict(checks: list[Check]) -> str:
    """The report's last line: all passed, which failed, or which could not be judged."""
    failed = [c.what for c in checks if c.status == "FAILED"]
    if failed:
        return "verdict: FAILED: " + "; ".join(failed)
    open_ = [c.what for c in checks if c.status == "inconclusive"]
    if open_:
        return ("verdict: no check failed; inconclusive (the reference cannot judge over this horizon): "
                + "; ".join(open_))
    return "verdict: all checks passed" + ("" if checks else " (none run)")


class ReportText:
    """The report as it is written: kept (``text()``), and echoed line by line to ``out`` when given."""

    def __init__(self, out: TextIO | None):
        self.buf = io.StringIO()
        self.out = out

    def __call__(self, line: str = "") -> None:
        self.buf.write(line + "\n")
        if self.out is not None:
            print(line, file=self.out, flush=True)

    def text(self) -> str:
        """Everything written so far."""
        return self.buf.getvalue()
