"""The leaderboard: a folder of score files (``pendulum-lqg score … --out FILE``) as one Markdown table.

One row per entry, one column group per suite — success rate, mean J of the successes, optimality
gap to the suite's reference — and a row per suite's reference and full-state bound underneath.
Entries are compared on a suite only when their suite fingerprints match the board's (the most
common one): a score made on another version of a suite, or with another episode count, is listed
under "Not comparable" instead of in the table.
"""

from __future__ import annotations

import json
from collections import Counter
from pathlib import Path
from typing import Any

from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.score import SCORE_VERSION
from pendulum_lqg.scoreboard.suites import SUITE_ORDER


def read_scores(folder: Path) -> list[tuple[Path, dict[str, Any]]]:
    """The score files (``*.json``) of ``folder``, checked for the keys the board reads."""
    folder = Path(folder)
    if not folder.is_dir():
        raise ConfigError(f"board: {folder} is not a folder of score files")
    out = []
    for path in sorted(folder.glob("*.json")):
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise ConfigError(f"board: {path} is not a readable score file ({exc})") from exc
        if not isinstance(data, dict) or data.get("score_version") != SCORE_VERSION \
                or not isinstance(data.get("suites"), dict) or not isinstance(data.get("policy"), str):
            raise ConfigError(f"board: {path} is not a score file of version {SCORE_VERSION} "
                              "(keys policy, score_version, suites)")
        out.append((path, data))
    if not out:
        raise ConfigError(f"board: {folder} holds no score files (*.json)")
    return out


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


def make_board(folder: Path) -> str:
    """The Markdown board of the score files in ``folder``."""
    scores = read_scores(folder)
    names = {n for _, d in scores for n in d["suites"]}
    suites = [n for n in SUITE_ORDER if n in names] + sorted(names - set(SUITE_ORDER))
    prints = {s: Counter(d["suites"][s]["fingerprint"] for _, d in scores if s in d["suites"])
              .most_common(1)[0][0] for s in suites}
    head = ["entry", "kind"] + [f"{s}: {c}" for s in suites for c in ("success", "J", "gap")]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    stale: list[str] = []
    for path, d in sorted(scores, key=lambda item: item[1]["policy"]):
        cells = [f"`{d['policy']}`", str(d.get("kind", ""))]
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
    return "\n".join(lines) + "\n"
