"""Scene reports: a measured deviation against a stated tolerance, and the text being written."""
from __future__ import annotations

import io
from dataclasses import dataclass
from typing import TextIO

__all__ = ["Check", "ReportText"]


@dataclass
class Check:
    """One comparison of the report: a max deviation against a stated tolerance."""

    what: str
    deviation: float
    tolerance: float
    seconds: str
    #: the effective body of a rotation against integrate_rotation, and that integration's seconds
    body: str = ""
    reference_seconds: float | None = None

    @property
    def ok(self) -> bool:
        """The deviation is within the tolerance."""
        return bool(self.deviation <= self.tolerance)

    def line(self) -> str:
        """The report line of this check."""
        return (f"  {self.what}: {self.deviation:.2e} (tolerance {self.tolerance:.1e}) [{self.seconds}]  "
                f"{'ok' if self.ok else 'FAILED'}")


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
