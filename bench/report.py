"""``latest.md``: the benchmark document as markdown tables, rendered from ``latest.json`` alone.

Rendering only from the JSON (never from live objects) keeps the two files in step, and lets
``python -m bench.report`` re-render an old result.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any

MET = {True: "met", False: "**MISSED**", None: "n/a"}


def _fmt(value: Any, digits: int = 3) -> str:
    if value is None:
        return "-"
    if isinstance(value, float):
        if value != value:
            return "-"
        return f"{value:.{digits}f}".rstrip("0").rstrip(".") if abs(value) < 1e6 else f"{value:.3g}"
    return str(value)


def _table(head: list[str], rows: list[list[Any]]) -> list[str]:
    lines = ["| " + " | ".join(head) + " |", "|" + "|".join("---" for _ in head) + "|"]
    lines += ["| " + " | ".join(_fmt(c) for c in row) + " |" for row in rows]
    return lines


def _section_note(section: dict[str, Any], run_started: str) -> str:
    """When the section was measured, if not in this run, and whether quickly."""
    notes = []
    if section.get("measured_at") and section.get("run_started") != run_started:
        notes.append(f"carried over from the run of {section.get('run_started')}")
    if section.get("quick"):
        notes.append("--quick: few repetitions, indicative only")
    if section.get("duration_s") is not None:
        notes.append(f"took {section['duration_s']:.0f} s")
    return f"_({'; '.join(notes)})_" if notes else ""


def _profile_lines(profile: dict[str, Any], what: str, top: int = 5) -> list[str]:
    areas = ", ".join(f"{name} {share * 100:.0f} %" for name, share in profile.get("area_share", {}).items()
                      if share >= 0.02)
    functions = "; ".join(f"`{f['function']}` {f['own_share'] * 100:.0f} %"
                          for f in profile.get("top_own_time", [])[:top])
    return [f"- {what}: own time by area: {areas}.", f"- Top functions by own time: {functions}."]


def tick_section(result: dict[str, Any], doc: dict[str, Any] | None = None) -> list[str]:
    """Benchmark 1."""
    rows = []
    for r in result["rows"]:
        convert = r.get("convert_ms") or {}
        cpu_ms = r.get("tree_cpu_ms") or {}
        rows.append([r["beams"], r["tree_ms"]["p50"], r["tree_ms"]["p99"], cpu_ms.get("p99"), r["baseline_ms"]["p50"],
                     r["baseline_ms"]["p99"], r["ratio_p50"], r["ratio_p99"], convert.get("p50"),
                     f"<= {r['target_p99_ms']}", MET[r["meets_target"]]])
    lines = _table(["beams", "tree p50 ms", "tree p99 ms", "tree p99 CPU ms", "if/else p50 ms", "if/else p99 ms",
                    "ratio p50",
                    "ratio p99", "LaserScan->Scan p50 ms", "target p99 ms", "target"], rows)
    first = result["rows"][0]
    lines += ["", f"{first['ticks']} ticks per size in {first.get('rounds', 1)} round(s) visiting the sizes in turn, "
              "each after a warm-up; tree and baseline alternating call by call "
              f"(maneuver {first['maneuver']}, tips {first['tips']}); GC on, as in the executive. \"CPU\" is the "
              "thread's CPU time (no preemption): a wall p99 far above it is other processes' load. The "
              "conversion of the ROS message happens once per scan in the executive's callback, outside the tick.",
              ""]
    lines += _tail_verdict(result["rows"], doc)
    prof = result.get("profile")
    if prof:
        lines.append(f"Profile (cProfile, {prof['ticks']} ticks at {prof['beams']} beams, "
                     f"{prof['profiled_ms_per_tick']} ms/tick under the profiler):")
        lines += _profile_lines(prof, "Tick")
    for item in result.get("already_removed", []):
        lines.append(f"- Already removed: {item}.")
    return lines


def _tail_verdict(rows: list[dict[str, Any]], doc: dict[str, Any] | None) -> list[str]:
    """One sentence on where the p99 comes from: the tree (CPU p99 near wall p99) or preemption."""
    pre = [r["beams"] for r in rows if (r.get("tree_cpu_ms") or {}).get("p99")
           and r["tree_ms"]["p99"] > 2 * r["tree_cpu_ms"]["p99"]]
    load = ""
    if doc is not None:
        load = (f" (load average {doc['run']['load_start'][0] if doc['run']['load_start'] else '?'} at the start "
                f"on {doc['machine']['cores']} cores)")
    if not pre:
        return ["Wall p99 is close to CPU p99 at every size: the tail is the tick's own cost (on a shared host "
                "that includes cache and SMT contention), not preemption.", ""]
    sizes = ", ".join(str(b) for b in pre)
    return [f"At {sizes} beams the wall p99 is more than twice the CPU p99: the tail is this process being "
            f"preempted by other processes{load}, not the tree; the CPU p99 is what the tree costs.", ""]


def latency_section(result: dict[str, Any], doc: dict[str, Any] | None = None) -> list[str]:
    """Benchmark 2."""
    rows = []
    for key, label in (("latency_ms", "scan published -> reflecting cmd_vel received (DDS)"),
                       ("to_published_ms", "scan published -> reflecting cmd_vel published (executive)"),
                       ("return_transport_ms", "cmd_vel published -> received"),
                       ("to_callback_ms", "scan published -> probe callback ran"),
                       ("tick_interval_ms", "interval between the executive's commands")):
        s = result[key]
        rows.append([label, s["n"], s["p50"], s["p90"], s["p99"], s["max"]])
    lines = _table(["measure", "n", "p50 ms", "p90 ms", "p99 ms", "max ms"], rows)
    lines += ["", f"{result['switches']} clear/blocked switches at random phases of the {result['tick_hz']:g} Hz "
              f"tick; misses (no reaction before the next switch): {result['misses']}; late pickups (a tick after "
              f"the scan was published still showed the old decision): {result['late_pickups']}. Target: p99 <= "
              f"{result['target_p99_ms']:g} ms (one period + 3 ms) -> {MET[_latency_met(result)]}. "
              f"Executive's own tick statistics (its exit line): {result.get('executive_tick_stats') or '-'}."]
    return lines


def _latency_met(result: dict[str, Any]) -> bool | None:
    p99 = result["latency_ms"]["p99"]
    if p99 is None or p99 != p99:
        return None
    return bool(p99 <= result["target_p99_ms"] and not result["misses"])


def sim_section(result: dict[str, Any], doc: dict[str, Any] | None = None) -> list[str]:
    """Benchmark 3."""
    lid = result["lidar"]
    lines = ["LiDAR (RayCaster.cast, homework LiDAR, stage_4):", ""]
    lines += _table(["beams", "segments + circles", "scans", "cast p50 us", "cast p99 us", "geometry only p50 us",
                     "scans/s (1/p50)", "scans/s aggregate"],
                    [[lid["beams"], f"{lid['segments']} + {lid['circles']}", lid["scans"], lid["cast_us"]["p50"],
                      lid["cast_us"]["p99"], lid["true_ranges_us"]["p50"], lid["scans_per_s"],
                      lid["scans_per_s_aggregate"]]])
    lock = result["lockstep"]
    lines += ["", f"Lock-step missions (run_mission {lock['world']}, maneuver {lock['maneuver']}, "
              f"config/homework.yaml, seeds 0-{lock['seeds'] - 1}, serial):", ""]
    lines += _table(["missions", "passed", "sim s", "wall p50 s", "wall min s", "wall max s",
                     "wall per 55 s mission", "speed (x real time)"],
                    [[len(lock["runs"]), sum(1 for r in lock["runs"] if r["passed"]), lock["sim_s_median"],
                      lock["wall_s"]["p50"], lock["wall_s"]["min"], lock["wall_s"]["max"],
                      lock["wall_per_55s_mission"], lock["rtf_median"]]])
    split = lock.get("split")
    if split:
        lines += ["", f"Without a profiler (median of seeds 0-{split['seeds'] - 1}): {split['wall_s']} s per mission, "
                  f"of which the tree's ticks {split['tree_tick_s']} s ({split['tick_share'] * 100:.0f} %, "
                  f"{split['tick_ms_mean']} ms per tick) and everything else (simulator physics and collision "
                  f"clearance, LiDAR, referee, the loop) {split['rest_s']} s: the lock-step target can only be "
                  "met when both parts fit in it."]
    prof = lock.get("profile")
    if prof:
        wall = lock["wall_s"]["p50"]
        parts = ", ".join(f"`{name}` {share * 100:.0f} % (~{share * wall:.2f} s)"
                          for name, share in prof["inclusive_share"].items() if share >= 0.01)
        lines += ["", f"Profile of one mission (cProfile, {prof['total_s']} s under the profiler, "
                  f"{lock['runs'][0]['ticks']} ticks of which {prof['armed_ticks']} armed):",
                  f"- Inclusive time of its parts (share, and that share of the median {wall} s mission): {parts}."]
        lines += _profile_lines(prof, "Mission")
    ros = result.get("ros", {})
    lines += ["", "ROS path (the sim hosting the referee + the executive over DDS, rtf 0, as `bt-nav demo`):", ""]
    if "skipped" in ros:
        lines.append(f"skipped: {ros['skipped']}")
        return lines
    rows = []
    for m in ros["missions"]:
        cpu = m.get("cpu_s") or {}
        rows.append([m.get("seed"), "PASSED" if m.get("passed") else "FAILED", m.get("mission_sim_s"),
                     m.get("mission_wall_s"), m.get("rtf"), m.get("startup_wall_s"), m.get("total_wall_s"),
                     m.get("cpu_span_wall_s"), cpu.get("executive"), cpu.get("sim"),
                     cpu.get("recorder"), m.get("executive_tick_stats"), m.get("error", "")])
    lines += _table(["seed", "verdict", "mission sim s", "mission wall s", "real-time factor", "start-up wall s",
                     "total wall s", "measured span wall s", "CPU s executive", "CPU s sim + referee",
                     "CPU s recorder", "executive's own tick stats", "error"], rows)
    lines += ["", f"Median real-time factor: {_fmt(ros['rtf_median'])}x (min {_fmt(ros['rtf_min'])}, "
              f"max {_fmt(ros['rtf_max'])}). CPU s: user + system from the robot seen by the recorder to the "
              "referee's verdict (the recorder: this process)."]
    prof = ros.get("executive_profile")
    if prof and "error" not in prof:
        parts = ", ".join(f"`{name}` {seconds:.2f} s" for name, seconds in prof["inclusive_s"].items() if seconds)
        lines += ["", f"Profile of the executive over one more mission (cProfile, wall clock, whole process; "
                  f"{prof['idle_s']:.1f} s idle in the executor's wait left out, {prof['total_s']:.1f} s busy; "
                  f"{_fmt(prof.get('ticks'))} ticks; real-time factor under the profiler "
                  f"{_fmt(prof.get('rtf_under_profiler'))}x):",
                  f"- Inclusive time: {parts}."]
        lines += _profile_lines(prof, "Executive", top=6)
    elif prof:
        lines += ["", f"Profile of the executive failed: {prof['error']}"]
    return lines


def quality_section(result: dict[str, Any], doc: dict[str, Any] | None = None) -> list[str]:
    """Benchmark 4: one table per grid (ideal and burger kinematics)."""
    lines: list[str] = []
    for name, grid in result["grids"].items():
        rows = []
        for s in grid["summary"]:
            failed = ", ".join(f"{check} x{n}" for check, n in s["failed_checks"].items()) or "-"
            rows.append([s["world"], s["maneuver"], f"{s['passed']}/{s['runs']}", s["collisions"],
                         round(s["travelled_median"], 2), round(s["travelled_min"], 2),
                         round(s["efficiency_median"], 3),
                         f"{s['efficiency_worst']:.3f} (seed {s['efficiency_worst_seed']})", failed])
        total = grid["overall"]
        lines += [f"**{name} kinematics, {grid['profile']} profile**: {total['passed']}/{total['runs']} passed "
                  f"({100 * total['pass_rate']:.1f} %), {total['collisions']} collisions, efficiency median "
                  f"{total['efficiency_median']:.3f} worst {total['efficiency_worst']:.3f}; "
                  f"{grid['missions']} missions in {grid['wall_s']} s ({result['jobs']} processes).", ""]
        lines += _table(["world", "maneuver", "passed", "collisions", "travelled med m", "travelled min m",
                         "efficiency med", "efficiency worst", "failed checks"], rows)
        lines.append("")
    lines.append("Efficiency = travelled / (max_linear_speed x time armed). Seeds 0..N-1 of `bt-nav grade`.")
    return lines


def memory_section(result: dict[str, Any], doc: dict[str, Any] | None = None) -> list[str]:
    """Benchmark 5."""
    if "skipped" in result:
        return [f"skipped: {result['skipped']}"]
    rows = []
    for m in result["missions"]:
        for name in ("executive", "sim"):
            status = m.get(name) or {}
            rows.append([m["seed"], name, _mb(status.get("VmHWM_kb")), _mb(status.get("VmRSS_kb"))])
    lines = _table(["mission seed", "process", "peak RSS (VmHWM) MB", "RSS at the verdict MB"], rows)
    lines += ["", f"Source: {result['source']}. Executive peak: median {_fmt(result['executive_vmhwm_mb_median'])} MB, "
              f"max {_fmt(result['executive_vmhwm_mb_max'])} MB."]
    after = result.get("executive_after_latency_run")
    if after:
        lines.append(f"Executive at the end of the latency benchmark ({_fmt(after.get('wall_s'))} s of 20 Hz ticking "
                     f"on wall time): VmHWM {_mb(after.get('VmHWM_kb'))} MB, VmRSS {_mb(after.get('VmRSS_kb'))} MB.")
    return lines


def _mb(kb: int | None) -> str:
    return "-" if not kb else f"{kb / 1024:.1f}"


def exe_section(result: dict[str, Any], doc: dict[str, Any] | None = None) -> list[str]:
    """Benchmark 7: one row per grade (rtf), then where a run's wall time and the grade's CPU went."""
    if "skipped" in result:
        return [f"skipped: {result['skipped']}"]
    rows, lines = [], []
    for g in result["grades"]:
        if "error" in g:
            lines.append(f"rtf {g.get('rtf')}: failed: `{g['error'][-300:]}`")
            continue
        p = g["phases_median"]
        cpu = ", ".join(f"{kind} {seconds / max(1, g['runs']):.1f}" for kind, seconds in g["cpu_by_kind_s"].items())
        rows.append([g["rtf"], f"{g['passed']}/{g['runs']}", g["wall_s"], g["missions_per_min"], p["wall_s"],
                     p["startup_s"], p["mission_s"], p["shutdown_s"], p["sim_rtf"], g.get("mission_bound_per_min"),
                     g["cpu_s_per_mission"], cpu,
                     f"{100 * g['cpu_share_of_cores']:.0f} %", "; ".join(g["reasons"]) or "-"])
    lines += _table(["rtf", "passed", "grade wall s", "missions/min", "run wall s (median)", "start-up s",
                     "mission s", "shutdown s", "sim rtf over the mission", "bound by the mission /min",
                     "CPU s per mission", "CPU s per mission by process",
                     "cores busy", "reasons of the failures"], rows)
    lines += ["", f"`bt-nav grade --exe '<venv>/bin/bt-nav executive' --worlds stage_4 --seeds {result['seeds']} "
              f"--jobs {result['jobs']}` in a subprocess. Per run (medians): start-up = run start to the judge's "
              "t0 (three Python processes up, the node's arm service found); mission = t0 to the verdict (~58 sim "
              "s over the rtf reached); shutdown = verdict to the run's end; bound by the mission = jobs x 60 / "
              "mission s, the throughput with instant start-up and shutdown. CPU: the grade and every process it "
              "started (exact), split by process from 0.25 s samples (the grade itself not in the split)."]
    return lines


def gradespeed_section(result: dict[str, Any], doc: dict[str, Any] | None = None) -> list[str]:
    """Benchmark 9 (issue 52), rendered by its module (:func:`bench.grade_speed.markdown`)."""
    if "skipped" in result:
        return [f"skipped: {result['skipped']}"]
    from .grade_speed import markdown

    return markdown(result)


SECTIONS = (
    ("tick", "1. Tick cost: tree vs hand-written if/else", tick_section),
    ("latency", "2. Reaction latency over DDS (scan -> cmd_vel)", latency_section),
    ("sim", "3. Simulator throughput", sim_section),
    ("quality", "4. Mission quality (referee, lock-step)", quality_section),
    ("memory", "5. Memory of the executive during a mission", memory_section),
    ("exe", "7. Grading throughput over DDS (`bt-nav grade --exe`)", exe_section),
    ("gradespeed", "9. Grading at real time, before and after issue 52 (`bt-nav grade`, lab grid)",
     gradespeed_section),
)


def history_section(history: list[dict[str, Any]]) -> list[str]:
    """The last runs (``bench/results/history.jsonl``) side by side: one row per target, one column per run,
    newest last, so a regression shows as a change along a row."""
    if not history:
        return []
    ids: list[str] = []
    for run in history:
        ids += [key for key in run.get("targets", {}) if key not in ids]
    head = ["target", "goal"] + [f"{run['started'][:16].replace('T', ' ')} {run.get('mode', '')} "
                                 f"`{run.get('commit', '?')}` load {(run.get('load_start') or ['?'])[0]}"
                                 for run in history]
    rows = []
    for key in ids:
        known = next(run["targets"][key] for run in reversed(history) if key in run.get("targets", {}))
        cells = []
        for run in history:
            t = run.get("targets", {}).get(key)
            cells.append("" if t is None else f"{_fmt(t['value'])} {MET[t['met']]}")
        rows.append([known["description"], known["goal"], *cells])
    return ["", "## History", "",
            f"The last {len(history)} runs of `make bench` / `python -m bench.run` (oldest first; each line of "
            "`bench/results/history.jsonl` is one run; an empty cell: not measured in that run). The machine is "
            "shared: compare along a row with the load in mind.", "", *_table(head, rows)]


def render(doc: dict[str, Any]) -> str:
    """The whole markdown document."""
    m = doc["machine"]
    run = doc["run"]
    lines = ["# bt_nav benchmarks", "",
             f"Run {run['started']} ({run['mode']}), {run['duration_s']:.0f} s: `{run['command']}`. "
             f"Load average (1/5/15 min) at the start {run['load_start']}, at the end {run['load_end']}: "
             "timings on a shared machine vary with the load; medians, p99 and same-run ratios are what to compare.",
             "", "## Machine", ""]
    lines += _table(["CPU", "cores (usable)", "OS", "Python", "numpy", "py_trees", "rclpy", "date"],
                    [[m["cpu"], f"{m['cores']} ({m['cores_usable']})", m["os"], m["python"], m["numpy"],
                      m["py_trees"], m["rclpy"], run["started"][:10]]])
    lines += ["", "## Targets", ""]
    lines += _table(["benchmark", "measure", "target", "value", "result"],
                    [[t["benchmark"], t["description"], t["goal"], f"{_fmt(t['value'])} {t['unit']}".strip(),
                      MET[t["met"]]] for t in doc["targets"]])
    lines += history_section(doc.get("history") or [])
    for key, title, render_section in SECTIONS:
        section = doc["benchmarks"].get(key)
        if section is None:
            continue
        lines += ["", f"## {title}", ""]
        note = _section_note(section, run["started"])
        if note:
            lines += [note, ""]
        if "error" in section:
            lines.append(f"failed: `{section['error']}`")
            continue
        lines += render_section(section["result"], doc)
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    """``python -m bench.report [latest.json]``: print the markdown of a result file."""
    args = sys.argv[1:] if argv is None else argv
    path = Path(args[0]) if args else Path(__file__).with_name("results") / "latest.json"
    print(render(json.loads(path.read_text(encoding="utf-8"))), end="")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
