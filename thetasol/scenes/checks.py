"""One line of a scene report: a measured deviation against a stated tolerance."""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["Check"]


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
