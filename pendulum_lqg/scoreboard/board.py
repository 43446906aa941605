"""The leaderboard: a folder of score files (``pendulum-lqg score … --out FILE``) as one Markdown table.

One row per entry, one column group per suite — success rate, mean J of the successes, optimality
gap to the suite's reference, failure-aware score (:mod:`pendulum_lqg.scoreboard.stats`) — and a
row per suite's reference and full-state bound underneath, then the row of what each suite's
designs are designed on (the score files' ``designed_on``:
:func:`~pendulum_lqg.scoreboard.suites.designed_on`). The failure-aware score is the one
``score`` stored (``n/a`` where the reference survived no episode, so it is undefined).

Score files that carry a ``method`` (the training runs of one method, one file per training seed:
``pendulum-lqg train`` writes the method and seed into the training record, and ``score
--agent sb3:MODEL.zip`` copies them) are also aggregated in a second table, one row per method:
per suite, the interquartile mean over the runs of the success rate and of the failure-aware
score, each with its stratified bootstrap 95 % interval (:func:`~pendulum_lqg.scoreboard.stats.aggregate`).
Entries are compared on a suite only when their suite fingerprints match the board's (the most
common one): a score made on another version of a suite, or with another episode count, is listed
under "Not comparable" instead of in the table.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from pendulum_lqg.boundary.schemas import SCORE_VERSION, score_file
from pendulum_lqg.errors import ConfigError
from pendulum_lqg.scoreboard.stats import aggregate
from pendulum_lqg.scoreboard.suites import SUITE_ORDER

Scores = list[tuple[Path, dict[str, Any]]]


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


def _score(entry: dict[str, Any]) -> str:
    mean = entry.get("score_mean")
    if mean is None:
        return "n/a"
    lo, hi = entry.get("score_ci", [None, None])
    return f"{mean:.2f}" + ("" if lo is None else f" [{lo:.2f}, {hi:.2f}]")


def _aggregate(values: list[float | None], fmt: Callable[[float], str]) -> str:
    if not values:
        return ""
    if any(v is None for v in values):
        return "n/a"
    agg = aggregate(np.array(values, dtype=float))
    lo, hi = agg["iqm_ci"]
    return f"{fmt(agg['iqm'])} [{fmt(lo)}, {fmt(hi)}]"


def method_runs(scores: Scores, repeated: list[str] | None = None,
                ) -> dict[str, dict[int | str, dict[str, Any]]]:
    """The score files that name a ``method``, by method and training seed (a file without a
    seed under its own name). Files of the same method and seed that played other suites are one
    run (their suites merged); a suite the same method and seed played again is not counted twice:
    the file is named in ``repeated``."""
    runs: dict[str, dict[int | str, dict[str, Any]]] = {}
    for path, d in sorted(scores, key=lambda item: item[0].name):
        if d.get("method") is None:
            continue
        seeds = runs.setdefault(d["method"], {})
        if d["seed"] in seeds:
            had = seeds[d["seed"]]
            new = {s: e for s, e in d["suites"].items() if s not in had["suites"]}
            if len(new) < len(d["suites"]) and repeated is not None:
                repeated.append(f"{path.name} (`{d['method']}` seed {d['seed']})")
            if new:
                seeds[d["seed"]] = {**had, "suites": {**had["suites"], **new}}
            continue
        seeds[path.name if d["seed"] is None else d["seed"]] = d
    return runs


def comparable(seeds: dict[int | str, dict[str, Any]], suite: str, prints: dict[str, str],
               ) -> list[dict[str, Any]]:
    """The suite entries of a method's runs that the board compares: applicable, and played on
    the board's version of ``suite`` (its fingerprint in ``prints``)."""
    return [d["suites"][suite] for d in seeds.values() if suite in d["suites"]
            and d["suites"][suite]["fingerprint"] == prints[suite]
            and d["suites"][suite].get("applicable", True)]


def board_fingerprints(scores: Scores, suites: list[str]) -> dict[str, str]:
    """Per suite, the fingerprint most of the score files were played on: the board's version."""
    return {s: Counter(d["suites"][s]["fingerprint"] for _, d in scores if s in d["suites"])
            .most_common(1)[0][0] for s in suites}


def methods_table(scores: Scores, suites: list[str], prints: dict[str, str]) -> list[str]:
    """The lines of the methods table (empty without a score file that names its ``method``):
    per method and suite, the IQM over its runs of success and failure-aware score, with their
    stratified bootstrap 95 % intervals. A second file of the same method and seed is not
    counted twice: it is named in a note under the table."""
    repeated: list[str] = []
    runs = method_runs(scores, repeated)
    if not runs:
        return []
    head = ["method", "runs (seeds)"] + [f"{_md(s)}: {c}" for s in suites for c in ("success",
                                                                                  "score")]
    lines = ["", "| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for method, seeds in sorted(runs.items()):
        listed = ", ".join(str(k) for k in sorted(k for k in seeds if isinstance(k, int)))
        cells = [f"`{_md(method)}`", f"{len(seeds)}" + (f" ({listed})" if listed else "")]
        for s in suites:
            entries = comparable(seeds, s, prints)
            fewer = f" (n = {len(entries)})" if 0 < len(entries) < len(seeds) else ""
            cells += [_aggregate([e["success_rate"] for e in entries], lambda v: f"{100 * v:.0f} %")
                      + fewer,
                      _aggregate([e["score_mean"] for e in entries], lambda v: f"{v:.2f}")]
        lines.append("| " + " | ".join(cells) + " |")
    lines += ["", "Methods: the runs of one method (score files with the same `method`, one per "
              "training seed). Per suite, the interquartile mean over the runs of the success rate "
              "and of the failure-aware score, each with its 95 % stratified bootstrap interval "
              "over runs (2 000 resamples); a suite that fewer of the method's runs played says how many "
              "(n = k)."]
    if repeated:
        lines += ["", "Counted once (the same method and seed again): " + "; ".join(repeated) + "."]
    return lines


def _reference_lines(scores: Scores, suites: list[str], prints: dict[str, str]) -> list[str]:
    """The rows of each suite's reference and full-state bound (from any comparable entry), and
    what the designs of each suite are designed on (from any comparable entry that says it)."""
    lines = []
    for label, key in (("reference", "reference"), ("full-state bound", "full_state_bound")):
        cells = [label, ""]
        for s in suites:
            e = next((d["suites"][s] for _, d in scores
                      if s in d["suites"] and d["suites"][s]["fingerprint"] == prints[s]
                      and d["suites"][s].get("applicable", True)), None)
            if e is None:
                cells += ["", "", "", ""]
                continue
            ref = e[key]
            cells += [_pct(ref["success_rate"]), _num(ref["cost_mean"]), f"`{ref['policy']}`", ""]
        lines.append("| " + " | ".join(cells) + " |")
    cells = ["designed on", ""]
    for s in suites:
        said = next((d["suites"][s]["designed_on"] for _, d in scores
                     if s in d["suites"] and d["suites"][s]["fingerprint"] == prints[s]
                     and d["suites"][s]["designed_on"] is not None), None)
        cells += ["" if said is None else _md(said), "", "", ""]
    lines.append("| " + " | ".join(cells) + " |")
    return lines


def board_scores(folder: Path, *, skipped: list[str] | None = None,
                 ) -> tuple[Scores, list[str], dict[str, str]]:
    """The score files of ``folder`` (:func:`read_scores`), the suites they hold in
    :data:`~pendulum_lqg.scoreboard.suites.SUITE_ORDER`, and the board's fingerprint of each
    (:func:`board_fingerprints`)."""
    scores = read_scores(folder, skipped=skipped)
    names = {n for _, d in scores for n in d["suites"]}
    suites = [n for n in SUITE_ORDER if n in names] + sorted(names - set(SUITE_ORDER))
    prints = board_fingerprints(scores, suites)
    return scores, suites, prints


def make_board(folder: Path, *, warn: Callable[[str], None] | None = None) -> str:
    """The Markdown board of the score files in ``folder``. Damaged files are skipped and listed
    under the table (and each reported to ``warn``, one line; see :func:`read_scores`)."""
    skipped: list[str] = []
    scores, suites, prints = board_scores(folder, skipped=skipped)
    for line in skipped:
        if warn is not None:
            warn(f"board: {line}")
    head = ["entry", "kind"] + [f"{_md(s)}: {c}" for s in suites
                                for c in ("success", "J", "gap", "score")]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    stale: list[str] = []
    for path, d in sorted(scores, key=lambda item: item[1]["policy"]):
        cells = [f"`{_md(d['policy'])}`", _md(d["kind"])]
        for s in suites:
            e = d["suites"].get(s)
            if e is not None and not e.get("applicable", True):
                cells += ["n/a", "", "", ""]
                continue
            if e is None or e.get("fingerprint") != prints[s]:
                if e is not None:
                    stale.append(f"`{d['policy']}` on `{s}` ({path.name}: suite fingerprint "
                                 f"{str(e.get('fingerprint'))[:12]}…)")
                cells += ["", "", "", ""]
                continue
            cells += [_pct(e["success_rate"]), _num(e["cost_mean"]), _gap(e), _score(e)]
        lines.append("| " + " | ".join(cells) + " |")
    lines += _reference_lines(scores, suites, prints)
    episodes = {s: next(d["suites"][s]["episodes"] for _, d in scores
                        if s in d["suites"] and d["suites"][s]["fingerprint"] == prints[s])
                for s in suites}
    lines += ["", "Episodes per suite: " + ", ".join(f"{s} {n}" for s, n in episodes.items())
              + ". Success: share of episodes without a failure; J: mean cost of the successful "
              "episodes; gap: mean J over the episodes both the entry and the suite's reference "
              "survived, divided by the reference's, minus one, with its 95 % paired bootstrap "
              "interval; score: the failure-aware score, the mean over all episodes of J_ref / J "
              "(0 for a failed episode; 1 = the reference), with its 95 % bootstrap interval "
              "over episodes (n/a: no rows of the suite's reference in the folder). Designed on: "
              "the model the suite's reference, its full-state bound and every built-in entry are "
              "designed on — the plant played where the suite fixes its plant (its LTI file for a "
              "plant given as matrices), the nominal MJCF where it randomises it (blank: score "
              "files that do not say)."]
    lines += methods_table(scores, suites, prints)
    if stale:
        lines += ["", "Not comparable (another suite version or episode count): "
                  + "; ".join(stale) + "."]
    if skipped:
        lines += ["", "Skipped (damaged score files): " + "; ".join(
            line.removeprefix("skipped ") for line in skipped) + "."]
    return "\n".join(lines) + "\n"
