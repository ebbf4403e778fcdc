"""Paper-vs-reproduction tables.

Every notebook ends with a :class:`ComparisonTable`.  ``table.display()`` renders it as Markdown in the notebook
and tags the output so that the notebook runner (:mod:`cislunar.publish.notebooks`) can gather all tables into
``build/report.md`` without parsing prose.
"""

from __future__ import annotations

from dataclasses import dataclass, field

from cislunar.publish.claims import STATUS_MEANINGS, STATUSES, Verdict, fmt

__all__ = ["ComparisonTable", "Row", "REPORT_METADATA_KEY", "STATUSES", "STATUS_MEANINGS", "fmt"]

#: Key placed in the display metadata of a rendered table.
REPORT_METADATA_KEY = "cislunar_report"


@dataclass
class Row:
    """One comparison: what the paper says, what we computed, and whether they agree (with the reason if not)."""

    quantity: str
    paper: str
    reproduced: str
    status: str
    note: str = ""


@dataclass
class ComparisonTable:
    """Paper value, reproduced value and status for each checked quantity of one notebook.

    Parameters
    ----------
    title : str
        Usually the notebook name and the paper section it follows.
    """

    title: str
    rows: list = field(default_factory=list)

    def __post_init__(self):
        if not isinstance(self.title, str):
            raise TypeError(f"title must be a str; got {type(self.title).__name__}")
        if not isinstance(self.rows, list):
            raise TypeError(f"rows must be a list of Row; got {type(self.rows).__name__}")

    def add(self, verdict, *more) -> "ComparisonTable":
        """Append judged claims (:class:`cislunar.publish.claims.Verdict`, from :meth:`Claim.judge`).

        The status word of a row is computed by the claim's rule, never typed by hand.
        """
        for v in (verdict, *more):
            if not isinstance(v, Verdict):
                raise TypeError("verdict must be a Verdict from Claim.judge (a status word is computed, not typed); got "
                                f"{type(v).__name__}")
            self.rows.append(Row(v.quantity, v.paper, v.reproduced, v.status, v.note))
        return self

    def to_markdown(self) -> str:
        """The table as GitHub-flavoured Markdown."""
        lines = [f"**{self.title}**", "", "| quantity | paper | reproduced | status | note |",
                 "|---|---|---|---|---|"]
        for r in self.rows:
            cells = [r.quantity, r.paper, r.reproduced, r.status, r.note]
            lines.append("| " + " | ".join(str(c).replace("|", "\\|").replace("\n", " ") for c in cells) + " |")
        return "\n".join(lines)

    def legend(self) -> str:
        """What the status words used in this table mean (Markdown, one line per word, in :data:`STATUSES` order)."""
        used = {r.status.split(":")[0].strip() for r in self.rows}
        return "\n".join(f"- **{w}**: {STATUS_MEANINGS[w]}" for w in STATUSES if w in used)

    def _repr_markdown_(self):
        return self.to_markdown()

    def display(self) -> None:
        """Show the table in a notebook, tagged for the report gatherer, then the legend of its status words (not
        tagged: ``build/report.md`` states the rule once in its header).  Falls back to printing."""
        md = self.to_markdown()
        legend = "*Status words in this table:*\n\n" + self.legend()
        try:
            from IPython.display import display
        except ImportError:  # pragma: no cover - IPython is a notebook dependency
            print(md + "\n\n" + legend)
            return
        display({"text/markdown": md, "text/plain": md}, raw=True, metadata={REPORT_METADATA_KEY: True})
        display({"text/markdown": legend, "text/plain": legend}, raw=True)
