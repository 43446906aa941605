"""The leaderboard: a folder of score files (``pendulum-lqg score … --out FILE``) as one Markdown table.

One row per entry, one column group per suite — success rate, mean J of the successes, optimality
gap to the suite's reference — and a row per suite's reference and full-state bound underneath.
Entries are compared on a suite only when their suite fingerprints match the board's (the most
common one): a score made on another version of a suite, or with another episode count, is listed
under "Not comparable" instead of in the table.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

from pendulum_lqg.boundary.schemas import SCORE_VERSION, score_file
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.suites import SUITE_ORDER


def read_scores(folder: Path, *, skipped: list[str] | None = None,
                ) -> list[tuple[Path, dict[str, Any]]]:
    """The score files (``*.json``) of ``folder``, each checked by
    :func:`~pendulum_lqg.boundary.schemas.score_file` for every key the board reads.

    A damaged file — not a regular file, not JSON, nested too deep, a key missing or of the wrong
    type — is skipped: one line naming it and the key is appended to ``skipped`` (or, without
    ``skipped``, it is a :class:`ConfigError`), so one bad file does not stop the board. A folder
    with no good score file is a :class:`ConfigError`."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ConfigError(f"board: {folder} is not a folder of score files")
    out = []
    for path in sorted(folder.glob("*.json")):
        try:
            out.append((path, score_file(path)))
        except ConfigError as exc:
            if skipped is None:
                raise
            why = str(exc).removeprefix(f"board: {path}").lstrip(": ")
            skipped.append(f"skipped {path.name}: {why}")
    if not out:
        raise ConfigError(f"board: {folder} holds no readable score file of version "
                          f"{SCORE_VERSION} (*.json)" + (f"; {skipped[0]}" if skipped else ""))
    return out


def _md(text: object) -> str:
    """``text`` safe in a Markdown table cell (one line, no column separator)."""
    return " ".join(str(text).split()).replace("|", "\\|")


def _pct(value: Any) -> str:
    return "–" if value is None else f"{100 * value:.0f} %"


def _num(value: Any, digits: int = 3) -> str:
    return "–" if value is None else f"{value:.{digits}g}"


def _gap(entry: dict[str, Any]) -> str:
    gap = entry.get("optimality_gap")
    if gap is None:
        return "–"
    lo, hi = entry.get("gap_ci", [None, None])
    ci = "" if lo is None else f" [{lo:+.2f}, {hi:+.2f}]"
    return f"{gap:+.2f}{ci}"


def make_board(folder: Path, *, warn: Callable[[str], None] | None = None) -> str:
    """The Markdown board of the score files in ``folder``. Damaged files are skipped and listed
    under the table (and each reported to ``warn``, one line; see :func:`read_scores`)."""
    skipped: list[str] = []
    scores = read_scores(folder, skipped=skipped)
    for line in skipped:
        if warn is not None:
            warn(f"board: {line}")
    names = {n for _, d in scores for n in d["suites"]}
    suites = [n for n in SUITE_ORDER if n in names] + sorted(names - set(SUITE_ORDER))
    prints = {s: Counter(d["suites"][s]["fingerprint"] for _, d in scores if s in d["suites"])
              .most_common(1)[0][0] for s in suites}
    head = ["entry", "kind"] + [f"{_md(s)}: {c}" for s in suites for c in ("success", "J", "gap")]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    stale: list[str] = []
    for path, d in sorted(scores, key=lambda item: item[1]["policy"]):
        cells = [f"`{_md(d['policy'])}`", _md(d["kind"])]
        for s in suites:
            e = d["suites"].get(s)
            if e is not None and not e.get("applicable", True):
                cells += ["n/a", "", ""]
                continue
            if e is None or e.get("fingerprint") != prints[s]:
                if e is not None:
                    stale.append(f"`{d['policy']}` on `{s}` ({path.name}: suite fingerprint "
                                 f"{str(e.get('fingerprint'))[:12]}…)")
                cells += ["", "", ""]
                continue
            cells += [_pct(e["success_rate"]), _num(e["cost_mean"]), _gap(e)]
        lines.append("| " + " | ".join(cells) + " |")
    for label, key in (("reference", "reference"), ("full-state bound", "full_state_bound")):
        cells = [label, ""]
        for s in suites:
            e = next((d["suites"][s] for _, d in scores
                      if s in d["suites"] and d["suites"][s]["fingerprint"] == prints[s]
                      and d["suites"][s].get("applicable", True)), None)
            if e is None:
                cells += ["", "", ""]
                continue
            ref = e[key]
            cells += [_pct(ref["success_rate"]), _num(ref["cost_mean"]), f"`{ref['policy']}`"]
        lines.append("| " + " | ".join(cells) + " |")
    episodes = {s: next(d["suites"][s]["episodes"] for _, d in scores
                        if s in d["suites"] and d["suites"][s]["fingerprint"] == prints[s])
                for s in suites}
    lines += ["", "Episodes per suite: " + ", ".join(f"{s} {n}" for s, n in episodes.items())
              + ". Success: share of episodes without a failure; J: mean cost of the successful "
              "episodes; gap: mean J over the episodes both the entry and the suite's reference "
              "survived, divided by the reference's, minus one, with its 95 % paired bootstrap "
              "interval."]
    if stale:
        lines += ["", "Not comparable (another suite version or episode count): "
                  + "; ".join(stale) + "."]
    if skipped:
        lines += ["", "Skipped (damaged score files): " + "; ".join(
            line.removeprefix("skipped ") for line in skipped) + "."]
    return "\n".join(lines) + "\n"
