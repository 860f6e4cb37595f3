"""One experiment report over campaigns already flown (run_experiments.py
--pool): each campaign directory's runs/ read again, runs paired by name
across campaigns, each campaign's setup lines kept and where the campaigns'
setups differ said in the report (an ablation differs on purpose; other
differences make the pairs compare unlike runs)."""
import os
import re
from typing import Dict, List, Optional, Sequence, Tuple

from . import experiments

#: Setup items of a campaign report that pooled campaigns should share (name, pattern on its setup lines).
SHARED_SETUP = (("house size", re.compile(r"\(generated houses ([^)]*)\)")),
                ("classes and sim limit", re.compile(r"classes (.*)$")),
                ("simulator overrides", re.compile(r"^simulator overrides: (.*)$")),
                ("node overrides", re.compile(r"^node overrides \(--extra-overrides\): (.*)$")),
                ("planner timing", re.compile(r"^planner: (.*)$")))


def parse_entry(entry: str, modes: Sequence[str]) -> Tuple[str, Optional[str], str]:
    """A --pool entry as (campaign directory, mode or None, '' or why it cannot be read).
    DIR:MODE takes MODE's runs of DIR; a directory whose own name holds a ':' is taken whole."""
    head, sep, tail = entry.rpartition(":")
    campaign, mode = entry, None
    if sep and not os.path.isdir(entry):
        if tail not in modes:
            return entry, None, "no directory %s, and %s is not one of --modes (%s)" % (entry, tail, " ".join(modes))
        campaign, mode = head, tail
    if not os.path.isdir(os.path.join(campaign, "runs")):
        return campaign, mode, "%s has no runs/ directory (not a campaign run_experiments.py flew)" % campaign
    return campaign, mode, ""


def campaign_setup(report_md: str) -> List[str]:
    """The setup lines of a campaign's report (its '- ' lines after the title; the detector is
    left to the pooled report, which names it from the runs); [] without a report."""
    if not os.path.exists(report_md):
        return []
    lines = []
    with open(report_md) as f:
        for line in f.read().splitlines()[2:]:
            if not line.startswith("- "):
                break
            if not line.startswith("- detector:"):
                lines.append(line[2:])
    return lines


def shared_setup(lines: Sequence[str]) -> Dict[str, str]:
    """The SHARED_SETUP items a campaign's setup lines state; an item a report leaves out is
    "not stated" (reports from before an option existed), and without lines nothing is known."""
    found = {}
    for name, pattern in SHARED_SETUP:
        for line in lines:
            m = pattern.search(line)
            if m:
                found[name] = m.group(1)
                break
        else:
            if lines:
                found[name] = "not stated"
    return found


def differences(setups: Sequence[Dict[str, str]]) -> List[str]:
    """Names of the SHARED_SETUP items that two or more campaigns state differently."""
    return [name for name, _ in SHARED_SETUP if len({s[name] for s in setups if name in s}) > 1]


def pool_report(entries: Sequence[Tuple[str, Optional[str]]], modes: Sequence[str], out: str,
                sim_limit_s: Optional[float] = None) -> Tuple[int, List[str]]:
    """Writes the report over the runs of `entries` ((campaign, mode or None) as parse_entry gives)
    into out; returns (0 or 1, messages). A run is read if it has timeseries.csv and summary.json
    (a mission stopped midway leaves only the first); sim_limit_s (s), if given, leaves out runs
    that ran far past it (experiments.implausible). A run name found in two campaigns fails the
    pool: runs are paired by name."""
    by_mode = {m: [] for m in modes}
    seen, setup, setups, msgs = {}, [], [], []
    for campaign, only in entries:
        n = 0
        runs_dir = os.path.join(campaign, "runs")
        for name in sorted(os.listdir(runs_dir)):
            mode = next((m for m in modes if name.endswith("_" + m)), None)
            d = os.path.join(runs_dir, name)
            if mode is None or (only and mode != only) or not os.path.isdir(d):
                continue
            if not all(os.path.exists(os.path.join(d, f)) for f in ("timeseries.csv", "summary.json")):
                msgs.append("run %s has no timeseries.csv or summary.json (stopped midway?); left out" % d)
                continue
            if name in seen:
                return 1, msgs + ["run %s is in both %s and %s; pairs go by run name" % (name, seen[name], campaign)]
            seen[name] = campaign
            try:
                run = experiments.read_run(d)
            except (OSError, ValueError, KeyError, TypeError, AttributeError) as e:  # a damaged summary or series
                msgs.append("run %s cannot be read (%s); left out" % (d, e))
                continue
            why = experiments.implausible(run, sim_limit_s if sim_limit_s is not None else float("inf"))
            if why:
                msgs.append("run %s: %s; left out of the curves" % (d, why))
                continue
            by_mode[mode].append(run)
            n += 1
        runs = only + " runs" if only else "runs"
        if n == 0:
            msgs.append("no usable %s in %s" % (runs, campaign))
        own = campaign_setup(os.path.join(campaign, "report.md"))
        setups.append(shared_setup(own))
        setup.append("pooled: %d %s of %s%s" % (n, runs, campaign, "".join("; " + line for line in own)))
    differ = differences(setups)
    if differ:
        setup.append("the pooled campaigns differ in: %s (pairs compare runs flown under different settings)"
                     % ", ".join(differ))
        msgs.append("the pooled campaigns differ in: %s" % ", ".join(differ))
    by_mode = {m: r for m, r in by_mode.items() if r}
    if not by_mode:
        return 1, msgs + ["no usable run"]
    experiments.write_outputs(os.path.abspath(out), by_mode, setup=setup)
    return 0, msgs + ["report: %s" % os.path.join(os.path.abspath(out), "report.md")]
