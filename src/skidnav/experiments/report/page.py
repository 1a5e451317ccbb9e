"""The page pieces of every report (``skidnav report``): the self-contained HTML shell and its
style, tables, embedded images, the closing config and provenance sections, the atomic write.

An experiment report (:mod:`skidnav.experiments.report.html`) and a study's report
(:func:`study_report`: the study's section, :meth:`skidnav.studies.kind.Study.report`, then the
resolved grid and the provenance) are built from these, so every report looks and is written
alike: one HTML file, figures embedded as base64, no scripts, no external links.
"""

from __future__ import annotations

import base64
import html
import json
import re
from collections.abc import Iterable
from pathlib import Path
from typing import Any

import pandas as pd

from skidnav.errors import UserError
from skidnav.experiments.provenance import CODE_KEYS, describe_code
from skidnav.experiments.store import ResultStore, RunLayout
from skidnav.files.atomic import remove_stale_temporaries, write_atomic
from skidnav.statistics.formatting import interval

STYLE = """
body{font-family:system-ui,sans-serif;max-width:1250px;margin:1.2em auto;padding:0 1em;color:#222}
h1{font-size:26px;margin:0.2em 0 0.4em}
#verdict{font-size:17px;line-height:1.4;margin:0 0 0.8em;padding:0.5em 0.8em;
 background:#eef6ee;border-left:5px solid #17631b}
.scroll{overflow-x:auto;max-width:100%;margin:0.6em 0}
table{border-collapse:separate;border-spacing:0;font-size:13px;font-variant-numeric:tabular-nums;
 border-top:1px solid #ccc;border-left:1px solid #ccc}
td,th{border-right:1px solid #ccc;border-bottom:1px solid #ccc;padding:3px 7px;text-align:right;
 vertical-align:top;background:#fff}
td:first-child{min-width:9em}
th{background:#f0f0f0} td:first-child,th:first-child{text-align:left}
td:first-child,th:first-child{position:sticky;left:0;z-index:1;box-shadow:1px 0 0 #999}
table.prose td,table.prose th{text-align:left;max-width:42em}
table.labels-2 td:nth-child(-n+2),table.labels-2 th:nth-child(-n+2),
table.labels-3 td:nth-child(-n+3),table.labels-3 th:nth-child(-n+3){text-align:left}
table.labels-2 td:nth-child(-n+2),table.labels-3 td:nth-child(-n+3){white-space:nowrap}
details{margin:0.6em 0} summary{cursor:pointer;font-weight:600}
img{max-width:100%} pre{background:#f6f6f6;padding:0.8em;overflow-x:auto;font-size:12px}
.yes{color:#17631b;font-weight:600} .no{color:#9b1c1c;font-weight:600}
.note{color:#555;font-size:13px}
"""
"""The report's style: numbers right-aligned in their columns, text left-aligned: the first
column, the first two or three of a table of class ``labels-2`` or ``labels-3``, every column of
one of class ``prose``. A table wider than the page scrolls sideways in its ``scroll`` box
(:func:`page` puts every table in one) with its first column, the row labels, fixed at the left
edge (``position: sticky``)."""


INTERVAL = re.compile(r"([\[(][^\[\]()<>\s]{1,40}), ([^\[\]()<>\s]{1,40}[\])])")
"""An interval's brackets (``[`` or ``(`` … ``]`` or ``)``) around two bounds and a comma."""


def interval_text(mean: float, low: float, high: float, digits: int | None = None) -> str:
    """``"12.3 [10.1, 14.2]"`` (:func:`skidnav.statistics.formatting.interval`: rounded for people,
    or to
    ``digits`` decimals); the estimate alone when the interval is undefined (one seed); "n/a"
    when the estimate is.

    >>> interval_text(12.3, 10.1, 14.2), interval_text(12.0, float("nan"), float("nan"))
    ('12.3 [10.1, 14.2]', '12')
    >>> interval_text(6819378.33, 6.1e6, 7.5e6), interval_text(float("nan"), 1.0, 2.0)
    ('6,820,000 [6,100,000, 7,500,000]', 'n/a')
    """
    return interval(mean, low, high, digits)


def image(png: bytes, alt: str) -> str:
    """An <img> tag embedding ``png`` as base64."""
    encoded = base64.b64encode(png).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/png;base64,{encoded}">'


def gif_image(gif: bytes, alt: str) -> str:
    """An <img> tag embedding an animated GIF as base64."""
    encoded = base64.b64encode(gif).decode("ascii")
    return f'<img alt="{html.escape(alt)}" src="data:image/gif;base64,{encoded}">'


def table(frame: pd.DataFrame, *, labels: int = 1, prose: bool = False, escape: bool = True) -> str:
    """An HTML table of preformatted string cells (``escape=False``: cells already HTML); its
    first ``labels`` columns (1–3) are text, left-aligned, the others numbers, right-aligned;
    ``prose``: every column left-aligned (cells of sentences)."""
    classes = "prose" if prose else (f"labels-{labels}" if labels in (2, 3) else None)
    if not prose:
        frame = frame.map(lambda cell: whole_intervals(cell) if isinstance(cell, str) else cell)
    return frame.to_html(index=False, escape=escape, border=0, classes=classes)


def whole_intervals(text: str) -> str:
    """``text`` with the space inside each interval ("[1.2, 3.4]", "[2.5, ∞)", "(0, 0.9]")
    made non-breaking, so a narrow column breaks a cell only before its interval.

    >>> whole_intervals("12.3 [10.1, 14.2]") == "12.3 [10.1,\u00a014.2]"
    True
    """
    return INTERVAL.sub("\\1,\u00a0\\2", text)


def sessions_table(metadata: dict[str, object]) -> str:
    """The sessions that wrote the results (start, code, runs done), and a warning when the runs
    come from more than one code version."""
    sessions = metadata.get("sessions")
    if not isinstance(sessions, list) or not sessions:
        return ""
    rows = [
        {
            "session started (UTC)": str(entry.get("started", "?")),
            "code": describe_code({key: entry.get(key) for key in CODE_KEYS}),
            "runs done": str(entry.get("runs_done", "?")),
            "completed": "yes" if entry.get("completed") else "no (killed or interrupted)",
        }
        for entry in sessions
    ]
    codes = {row["code"] for row in rows if row["runs done"] not in ("0", "?")}
    warning = (
        f"<p class='no'>These results were produced by {len(codes)} different code versions.</p>"
        if len(codes) > 1
        else ""
    )
    return warning + table(pd.DataFrame.from_records(rows))


TABLE = re.compile(r"<table\b.*?</table>", re.DOTALL)
"""An HTML table, from its opening tag to its end (a report's tables never nest)."""


def page(title: str, body: Iterable[str]) -> str:
    """One self-contained HTML page: ``title`` and the ``body`` fragments, in the report's
    style, every table in a box that scrolls sideways (``<div class='scroll'>``, :data:`STYLE`),
    whoever wrote it (the report's :func:`table` or a study's own).

    >>> "<div class='scroll'><table><tr><td>1</td></tr></table></div>" in page(
    ...     "t", ["<table><tr><td>1</td></tr></table>"]
    ... )
    True
    """
    text = TABLE.sub(lambda table: f"<div class='scroll'>{table.group(0)}</div>", "".join(body))
    return (
        "<!DOCTYPE html><html><head><meta charset='utf-8'><link rel='icon' href='data:,'>"
        f"<title>{html.escape(title)}</title><style>{STYLE}</style></head>"
        f"<body>{text}</body></html>"
    )


def config_and_provenance(config: dict[str, Any], metadata: dict[str, Any]) -> list[str]:
    """The closing sections of a report: the resolved ``config`` (as saved in ``config.json``),
    folded, and the provenance of ``metadata.json`` (sessions, package versions)."""
    text = json.dumps(config, indent=2)
    return [
        "<h2>Config (resolved)</h2>",
        "<details class='config'><summary>the resolved config, as saved in config.json "
        f"({text.count(chr(10)) + 1} lines)</summary><pre>{html.escape(text)}</pre></details>",
        "<h2>Provenance</h2>",
        sessions_table(metadata),
        f"<pre>{html.escape(json.dumps(metadata.get('versions', {}), indent=2))}</pre>",
    ]


def study_report(run_dir: Path | str, layout: RunLayout, fragment: str) -> str:
    """The report page of a study's results directory (of the kind ``layout``): a title, the
    study's section ``fragment`` (:meth:`skidnav.studies.kind.Study.report`), then the resolved
    grid and the provenance, as in an experiment report."""
    store = ResultStore(run_dir, layout)
    grid = store.config()
    name = str(getattr(grid, "name", Path(run_dir).name))
    body = [
        f"<h1>skidnav {html.escape(layout.kind)}: {html.escape(name)}</h1>",
        fragment,
        *config_and_provenance(layout.to_dict(grid), store.metadata()),
    ]
    return page(f"skidnav: {name}", body)


def markdown_html(text: str) -> str:
    """The HTML of the markdown a study writes (``#`` headings, pipe tables, paragraphs), its
    text escaped; a heading one level lower than written (a report's sections are ``<h2>``).

    >>> text = markdown_html("Means <n>.\\n## Rates\\n| agent | rate |\\n|---|---:|\\n| q | 0.5 |")
    >>> text.split("<table>")[0]
    "<p class='note'>Means &lt;n&gt;.</p><h3>Rates</h3>"
    >>> "<th>rate</th>" in text and "<td>0.5</td>" in text and "---" not in text
    True
    """
    parts: list[str] = []
    rows: list[list[str]] = []
    for line in [*text.splitlines(), ""]:
        stripped = line.strip()
        if stripped.startswith("|"):
            cells = [cell.strip() for cell in stripped.strip("|").split("|")]
            if not all(set(cell) <= set("-: ") for cell in cells):  # not the separator row
                rows.append(cells)
            continue
        if rows:
            parts.append(_html_table(rows))
            rows = []
        if stripped.startswith("#"):
            level = min(len(stripped) - len(stripped.lstrip("#")) + 1, 6)
            heading = html.escape(stripped.lstrip("#").strip())
            parts.append(f"<h{level}>{heading}</h{level}>")
        elif stripped:
            parts.append(f"<p class='note'>{html.escape(stripped)}</p>")
    return "".join(parts)


def _html_table(rows: list[list[str]]) -> str:
    """An HTML table of escaped text cells, the first row the header."""
    header = "".join(f"<th>{html.escape(cell)}</th>" for cell in rows[0])
    body = "".join(
        "<tr>" + "".join(f"<td>{html.escape(cell)}</td>" for cell in row) + "</tr>"
        for row in rows[1:]
    )
    return f"<table><thead><tr>{header}</tr></thead><tbody>{body}</tbody></table>"


def report_path(run_dir: Path | str, output: Path | str | None = None) -> Path:
    """Where the report of ``run_dir`` goes: ``output``, else ``RUN_DIR/report.html``."""
    return Path(output) if output is not None else Path(run_dir) / "report.html"


def write_page(path: Path | str, text: str) -> Path:
    """Write the page ``text`` to ``path`` atomically, so a kill leaves the previous report or
    none, never part of one; returns its path. Temporaries left beside it by report writers
    that died are removed first.

    Raises:
        UserError: the report cannot be written there.
    """
    path = Path(path)
    remove_stale_temporaries(path.parent, path.name)
    try:
        write_atomic(path, text.encode("utf-8"))
    except OSError as error:
        raise UserError(f"{path}: cannot write the report ({error.strerror or error})") from None
    return path
