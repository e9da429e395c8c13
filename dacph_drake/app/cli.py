"""Command line: ``dacph COMMAND ...`` (``dacph --help`` lists the commands)."""
import argparse
import logging
import signal
import sys
from typing import Optional, Sequence

import numpy as np

from dacph_drake.loop.threads import single_threaded
from dacph_drake.controllers import (NAMES as CONTROLLERS, REFERENCE, REGISTRY,
                                     build_closed_loop)
# The built-in scenarios' names (scenario.BUILT_IN_SCENARIOS), without loading Drake.
BUILT_IN_SCENARIO_NAMES = ("paper", "short", "satellite_6dof", "satellite_3dof")
from dacph_drake.scenario.errors import ConfigError, require_nonnegative, require_positive

DESCRIPTION = ("Data-Assisted Control in the port-Hamiltonian framework (DAC-pH) on "
               "free-floating manipulators: simulate, reproduce, report, verify and "
               "sweep closed loops of any arm. 'dacph COMMAND --help' shows a "
               "command's arguments.")


def _free_flight(args) -> int:
    from dacph_drake.app.free_flight import run_free_flight
    from dacph_drake.scenario.planar_arm import RobotParams, load_robot
    require_positive("--duration", args.duration, "s")
    robot = load_robot(args.robot) if args.robot else RobotParams()
    n = robot.num_links
    result = run_free_flight(robot, args.duration, amplitudes=np.full(n, 0.006),
                             frequencies=3.0 + np.arange(n), q0=np.full(n, 0.3))
    drift = abs(result.kinetic_energy - result.work) / max(result.kinetic_energy, 1e-300)
    print(f"free flight, {args.duration:g} s, {n} links")
    print(f"  max |momentum|            {result.max_momentum:.3e}  (zero at start)")
    print(f"  kinetic energy            {result.kinetic_energy:.9e} J")
    print(f"  work done by torques      {result.work:.9e} J")
    print(f"  relative energy mismatch  {drift:.3e}")
    print(f"  min arm-base clearance    {result.min_clearance:.4f} m")
    return 0


def _simulate(args) -> int:
    from pathlib import Path
    from dacph_drake.assembly.registry import robot_of
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.assembly.scenario_files import load_scenario
    scenario = load_scenario(args.scenario)
    meshcat = _LiveViewing(args, scenario)
    result = simulate(scenario, args.controller, duration=args.duration,
                      out_dir=args.out, progress=not args.quiet, interruptible=True,
                      checkpoint_seconds=args.checkpoint, meshcat=meshcat)
    print(f"{args.controller}: {result.status}{': ' + result.reason if result.reason else ''}"
          f" ({result.final_time:.2f} s simulated in {result.wall_time:.1f} s)")
    summary = (_report_run(Path(args.out), args.controller)
               if len(result.logs["time"]) > 1 else None)
    if summary and result.final_time > scenario.phases.linear_start:
        if not args.quiet:
            _print_metrics(summary["metrics"][args.controller], scenario,
                           result.final_time)
        if "learner_log" in result.logs:
            from dacph_drake.loop.metrics import learning_report
            for text in learning_report(result.logs, scenario)["warnings"]:
                print(f"dacph: warning: {text}", file=sys.stderr)
    if summary:
        print(f"panels in {Path(args.out) / 'figures'} ({len(summary['figures'])} PNG); "
              f"metrics in {Path(args.out) / 'metrics.json'}")
    if args.animate and len(result.logs["time"]) > 1:
        print(robot_of(scenario).WriteAnimation(
            result.logs, Path(args.out) / f"animation_{args.controller.replace('-', '_')}"
                                           ".html"))
    print(f"saved to {args.out}")
    _KeepViewerOpen(meshcat)
    return {"ok": 0, "interrupted": 130}.get(result.status, 1)


def _report_run(out, controller: str) -> dict:
    """The report of a new run with the directory's runs of its duration; its summary."""
    from dacph_drake.app.reproduce import report, runs_in
    from dacph_drake.loop.run_store import load_run_meta
    duration = load_run_meta(out, controller)["duration"]
    together, apart = [], []
    for other in runs_in(out):
        try:
            record = load_run_meta(out, other)
        except ConfigError:
            record = {}
        (together if record.get("duration") == duration else apart).append(other)
    if apart:
        print(f"dacph: note: the report in {out} leaves out the {', '.join(apart)} "
              f"run{'s' if len(apart) > 1 else ''} (another duration or unreadable)",
              file=sys.stderr)
    return report(out, together, formats=("png",))


def _print_metrics(flat, scenario, final_time: float) -> None:
    """A run's metrics, then by phase, each with its unit and metrics.json key."""
    from dacph_drake.loop.metrics import PHASE_NAMES, RunMetrics
    record = RunMetrics.FromFlat(flat)
    p = scenario.phases
    spans = dict(zip(PHASE_NAMES, ((p.linear_start, p.nonlinear_start),
                                   (p.nonlinear_start, p.disturbance_start),
                                   (p.disturbance_start, p.end))))
    groups = [("run (phases 1-3)", "", record.run, final_time)] + [
        (f"{key}: {name}, {spans[key][0]:g}-{spans[key][1]:g} s", f"{key}.",
         record.phases[name], final_time if final_time > spans[key][0] else None)
        for key, name in PHASE_NAMES.items()]
    for title, prefix, values, reached in groups:
        print(f"  {title}")
        if reached is None:
            print(f"    {prefix + '*':44s} n/a, not reached (the run ended at "
                  f"{final_time:g} s)")
            continue
        for name, value in values.items():
            unit = record.units.get(name, "")
            text = f"{value:.6g}{' ' + unit if unit else ''}" if value == value else "n/a"
            print(f"    {prefix + name:44s} {text}")


def _spatial(args) -> int:
    """The command before `dacph simulate` ran every robot: the same run, with a note."""
    if args.panels:
        raise ConfigError("--panels: dacph spatial is now dacph simulate; allowed: "
                          f"dacph reproduce {args.scenario} --out DIR (every controller, "
                          "its tables and panels)")
    print("dacph: note: dacph spatial is dacph simulate now (any scenario, planar or "
          "described)", file=sys.stderr)
    return _simulate(args)


def _diagram(args) -> int:
    from pathlib import Path
    from dacph_drake.app.graph import render_diagram
    from dacph_drake.atomic_files import prepare_out_dir
    from dacph_drake.assembly.scenario_files import load_scenario
    scenario = load_scenario(args.scenario)
    out = prepare_out_dir(args.out) if args.out else Path.cwd()
    controllers = [args.controller] if args.controller else list(CONTROLLERS)
    for controller in controllers:
        loop = build_closed_loop(controller, scenario)
        stem = out / f"{Path(args.scenario).stem}_{controller.replace('-', '_')}"
        for path in render_diagram(loop.diagram, stem):
            print(path)
    return 0


def _print_table(summary) -> None:
    from dacph_drake.app.reproduce import NOT_REACHED, format_value
    for row in summary["table"]:
        print(f"  {row['metric']:52s} paper {format_value(row['paper'], row['unit']):>14s}"
              f"   here {format_value(row['this_project'], row['unit']):>14s}")
    if summary["ablation"]:
        print(f"  {'per phase:':52s} {'1':>14s} {'2':>14s} {'3':>14s}")
    for row in summary["ablation"]:
        print(f"  {row['metric']:52s} " + " ".join(
            f"{format_value(v, row['unit'], NOT_REACHED):>14s}" for v in row["phases"]))


def _animate_run(run_dir, controller: str, out=None):
    from pathlib import Path
    from dacph_drake.assembly.registry import robot_of
    from dacph_drake.loop.run_store import load_run
    logs, scenario, _ = load_run(run_dir, controller)
    out = (Path(out) if out else
           Path(run_dir) / f"animation_{controller.replace('-', '_')}.html")
    return robot_of(scenario).WriteAnimation(logs, out)


def _reproduce(args) -> int:
    import time
    from dacph_drake.app.reproduce import reproduce
    from dacph_drake.assembly.scenario_files import load_scenario
    name = args.scenario or ("short" if args.quick else "paper")
    start = time.perf_counter()
    summary = reproduce(load_scenario(name), args.out, progress=not args.quiet,
                        jobs=args.jobs)
    print(f"reproduced {name} in {time.perf_counter() - start:.0f} s -> {args.out}")
    _print_table(summary)
    if args.animate:
        print(_animate_run(args.out, REFERENCE))
    return 0 if all(r["status"] == "ok" for r in summary["runs"].values()) else 1


def _report(args) -> int:
    from dacph_drake.app.reproduce import REQUIRED, report
    from dacph_drake.assembly.scenario_files import load_saved_scenario
    summary = report(args.run_dir)
    if summary["table"]:
        _print_table(summary)
    else:
        scenario = load_saved_scenario(f"{args.run_dir}/scenario.yaml")
        for controller, flat in summary["metrics"].items():
            print(f"{controller} ({summary['runs'][controller]['status']})")
            _print_metrics(flat, scenario, summary["runs"][controller]["final_time"])
        if summary["ablation"]:
            _print_table({"table": [], "ablation": summary["ablation"]})
    print(f"panels in {args.run_dir}/figures; tables in metrics.md, ablation.md, "
          "metrics.json" + ("" if summary["table"] else
                            f" (the comparison with the paper needs the "
                            f"{' and '.join(REQUIRED)} runs)"))
    return 0


def _animate(args) -> int:
    print(_animate_run(args.run_dir, args.controller, args.out))
    return 0


EXPORT_FORMATS = ("csv", "parquet")


def _export(args) -> int:
    """A saved run's logs as a pandas table: a row per logged time (RunResult.to_pandas)."""
    from pathlib import Path
    from dacph_drake.atomic_files import replaced_atomically
    from dacph_drake.loop.run_store import RunResult, load_run
    logs, scenario, meta = load_run(args.run_dir, args.controller)
    run = RunResult(args.controller, meta["status"], meta.get("reason", ""),
                    meta["final_time"], meta.get("wall_time", float("nan")), logs,
                    scenario=scenario)
    try:
        frame = run.to_pandas(args.signals or ())
    except ImportError as e:
        raise ConfigError(f"--format {args.format} needs pandas ({e}); allowed: pip "
                          "install 'dacph-drake[pandas,parquet]'") from e
    except KeyError as e:
        raise ConfigError(f"--signals: {e.args[0]}") from e
    out = (Path(args.out) if args.out else Path(args.run_dir) /
           f"logs_{args.controller}.{args.format}")
    if out.is_dir():
        raise ConfigError(f"--out = {str(out)!r} is a directory; allowed: a file")
    try:
        with replaced_atomically(out) as path:
            if args.format == "csv":
                frame.to_csv(path)
            else:
                frame.to_parquet(path)
    except ImportError as e:
        raise ConfigError(f"--format parquet needs pyarrow ({e}); allowed: --format "
                          "csv, or pip install 'dacph-drake[parquet]'") from e
    except OSError as e:
        raise ConfigError(f"--out = {str(out)!r} cannot be written ({e.strerror}); "
                          "allowed: a file in a writable directory") from e
    print(f"{out} ({len(frame)} rows x {frame.shape[1]} columns)")
    return 0


def _verify(args) -> int:
    """Verifies a run directory (or first simulates DAC into --out); exit 1 on a failure."""
    from pathlib import Path
    from dacph_drake.loop.verify import verify_run
    from dacph_drake.loop.simulate import simulate
    from dacph_drake.assembly.scenario_files import load_scenario
    target = Path(args.target)
    if target.is_dir():
        run_dir = target
    else:
        scenario = load_scenario(args.target)
        if not args.out:
            raise ConfigError("--out is required when verifying a scenario (the DAC "
                              "run is saved there)")
        run_dir = Path(args.out)
        result = simulate(scenario, args.controller, out_dir=run_dir,
                          progress=not args.quiet, interruptible=True)
        if result.status == "interrupted":
            print(f"{args.controller}: interrupted ({result.reason}; "
                  f"{result.final_time:.2f} s simulated), saved to {run_dir}; not "
                  "verified", file=sys.stderr)
            return 130
    require_positive("--region-budget", args.region_budget, "s")
    report = verify_run(run_dir, controller=args.controller,
                        region_budget=args.region_budget)
    for name, check in report["checks"].items():
        detail = (check.get("reason") or check.get("first_failure")
                  or (f"skipped: {check['skipped']}" if check.get("skipped") else ""))
        print(f"  {name:22s} {'ok' if check['ok'] else 'FAILED'}  {detail}")
    skipped = sum(bool(check.get("skipped")) for check in report["checks"].values())
    print(f"{'PASS' if report['ok'] else 'FAIL'}"
          f"{f' ({skipped} check skipped)' if skipped else ''}: report in "
          f"{run_dir / 'verification.md'}")
    return 0 if report["ok"] else 1


def _sweep(args) -> int:
    from dacph_drake.montecarlo.definition import load_sweep
    from dacph_drake.montecarlo.executors import InProcessExecutor, dask_executor
    from dacph_drake.montecarlo.runner import run_sweep
    from dacph_drake.montecarlo.store import read_rows
    from dacph_drake.montecarlo.summary import format_summary, write_summary
    definition = load_sweep(args.sweep)
    if args.workers is not None and args.workers < 0:
        raise ConfigError(f"--workers = {args.workers}; allowed: >= 0 (0: in this process)")
    if args.batch_size is not None and not 1 <= args.batch_size <= 4096:
        raise ConfigError(f"--batch-size = {args.batch_size}; allowed: 1 to 4096 trials "
                          "per diagram")
    if not args.report:
        try:
            if args.dask:
                with dask_executor(args.dask, args.workers) as (executor, slots):
                    run_sweep(definition, args.out, executor, slots,
                              progress=not args.quiet, batch_size=args.batch_size)
            elif args.workers == 0:
                run_sweep(definition, args.out, InProcessExecutor(), 1,
                          progress=not args.quiet, batch_size=args.batch_size)
            else:
                run_sweep(definition, args.out, slots=args.workers,
                          progress=not args.quiet, batch_size=args.batch_size)
        except KeyboardInterrupt:
            print(f"\ninterrupted: {len(read_rows(args.out))} trials saved in {args.out}; "
                  "run the same command to resume", file=sys.stderr)
            return 130
    summary = write_summary(args.out, definition)
    print(format_summary(summary), end="")
    print(f"saved to {args.out}")
    if summary["trials"] and summary["succeeded"] == 0:
        print(f"dacph: error: none of the {summary['trials']} trials ran to the end "
              f"(reasons in {args.out}/rows.jsonl)", file=sys.stderr)
        return 1
    return 0


def _AddLiveViewing(command) -> None:
    command.add_argument("--meshcat", action="store_true",
                         help="show the robot live in a Meshcat browser window (the URL "
                              "is printed)")
    command.add_argument("--realtime-rate", type=float, default=None, metavar="RATE",
                         help="pace the simulation at RATE x real time (sets "
                              "simulator.target_realtime_rate; 0: as fast as possible)")


def _LiveViewing(args, scenario):
    """Applies --realtime-rate; with --meshcat, a Meshcat (its URL printed), else None."""
    if args.realtime_rate is not None:
        require_nonnegative("--realtime-rate", args.realtime_rate)
        scenario.simulator.target_realtime_rate = args.realtime_rate
    if not args.meshcat:
        return None
    from dacph_drake.robots.viewers import QuietMeshcat
    meshcat = QuietMeshcat()
    print(f"Meshcat: open {meshcat.web_url()} to watch the run", flush=True)
    return meshcat


def _KeepViewerOpen(meshcat) -> None:
    if meshcat is not None and sys.stdin.isatty():
        input(f"Meshcat still shows the run at {meshcat.web_url()}; press Enter to "
              "close it. ")


RUN_DIR_HELP = "a run directory written by dacph simulate or reproduce"
SCENARIO_HELP = ("scenario YAML (e.g. scenarios/short.yaml) or a built-in name: "
                 f"{', '.join(BUILT_IN_SCENARIO_NAMES)}")


def _AddSimulateArguments(command) -> None:
    command.add_argument("--out", required=True, metavar="DIR",
                         help="run directory (created if missing): logs_CONTROLLER.npz, "
                              "run_CONTROLLER.json, scenario.yaml, figures/ (the run's "
                              "panels, PNG and PDF), metrics.json, metrics.md, "
                              "ablation.md")
    _AddController(command, "the closed loop to simulate")
    command.add_argument("--duration", type=float, default=None, metavar="SECONDS",
                         help="simulated time [s] (default: the scenario's phases)")
    command.add_argument("--checkpoint", type=float, default=60.0, metavar="SECONDS",
                         help="save the logs so far every SECONDS of wall time (status "
                              "'incomplete' until the run ends; default: %(default)g)")
    command.add_argument("--animate", action="store_true",
                         help="also write an HTML replay of the run "
                              "(animation_dac.html, animation_dac_nominal.html or "
                              "animation_model_based.html)")
    _AddLiveViewing(command)


def _AddController(command, what: str, default: Optional[str] = REFERENCE) -> None:
    command.add_argument(
        "--controller", choices=CONTROLLERS, default=default,
        help=f"{what} (default: {default or 'all'}); " + "; ".join(
            f"{name}: {c.description}" for name, c in REGISTRY.items()))


class _Parser(argparse.ArgumentParser):
    """argparse's parser, naming the closest allowed value after an invalid choice."""

    def error(self, message: str):
        import difflib
        import re
        match = re.search(r"invalid choice: '([^']*)' \(choose from (.*)\)", message)
        if match:
            allowed = re.findall(r"'([^']*)'", match.group(2))
            close = difflib.get_close_matches(match.group(1), allowed, n=1)
            if close:
                message += f"; did you mean {close[0]!r}?"
        super().error(message)


class _Once(logging.Filter):
    """Lets each distinct message through once (a description is parsed twice)."""

    def __init__(self):
        super().__init__()
        self.seen = set()

    def filter(self, record: logging.LogRecord) -> bool:
        message = record.getMessage()
        first = message not in self.seen
        self.seen.add(message)
        return first


def _ShowNotes(quiet: bool) -> None:
    """Logged notes and Drake's warnings on stderr as "dacph: note: ...", each once; with
    --quiet, errors only; an embedding application's handlers are left as set."""
    root = logging.getLogger()
    if root.handlers:
        return
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("dacph: note: %(message)s"))
    handler.addFilter(_Once())
    root.addHandler(handler)
    root.setLevel(logging.ERROR if quiet else logging.WARNING)


def _version() -> str:
    """The installed package's version (its metadata; "unknown" if not installed)."""
    from importlib.metadata import PackageNotFoundError, version
    try:
        return version("dacph-drake")
    except PackageNotFoundError:
        return "unknown"


def make_parser() -> argparse.ArgumentParser:
    """The ``dacph`` parser: every command with its arguments, each with its help."""
    parser = _Parser(prog="dacph", description=DESCRIPTION)
    parser.add_argument("--version", action="version",
                        version=f"%(prog)s {_version()}")
    parser.add_argument("--quiet", action="store_true",
                        help="no progress bars, notes or metric listings: the outcome "
                             "line, the files written, warnings and errors only")
    commands = parser.add_subparsers(dest="command", metavar="COMMAND",
                                     parser_class=_Parser,
                                     help="'dacph COMMAND --help' for its arguments")
    free = commands.add_parser(
        "free-flight", help="passive simulation of the ground truth: momentum and "
                            "energy bookkeeping")
    free.add_argument("--robot", metavar="YAML",
                      help="planar robot YAML (default: the paper's two-link arm)")
    free.add_argument("--duration", type=float, default=10.0, metavar="SECONDS",
                      help="simulated time [s] (default: %(default)g)")
    free.set_defaults(run=_free_flight)
    sim = commands.add_parser("simulate", help="simulate a closed loop of any robot; "
                                               "save its logs, panels and metrics")
    sim.add_argument("scenario", help=SCENARIO_HELP)
    _AddSimulateArguments(sim)
    sim.set_defaults(run=_simulate)
    graph = commands.add_parser("diagram", help="render the diagram graph (SVG, PNG)")
    graph.add_argument("scenario", help=SCENARIO_HELP)
    _AddController(graph, "the closed loop to draw", default=None)
    graph.add_argument("--out", default=None, metavar="DIR",
                       help="folder for SCENARIO_CONTROLLER.svg, .png and .dot "
                            "(default: the current directory)")
    graph.set_defaults(run=_diagram)
    rep = commands.add_parser(
        "reproduce", help="run DAC, its learning ablation (dac-nominal) and the "
                          "model-based baseline, write the paper's panels, the metrics "
                          "table beside the paper's numbers and the ablation table")
    rep.add_argument("scenario", nargs="?", default=None,
                     help=SCENARIO_HELP + " (default: paper, 1500 s; short with --quick)")
    rep.add_argument("--out", required=True, metavar="DIR",
                     help="run directory: every controller's run files, figures/, "
                          "metrics.md, ablation.md, metrics.json, scenario.yaml")
    rep.add_argument("--quick", action="store_true",
                     help="the short scenario (26 s) instead of the paper's")
    rep.add_argument("--animate", action="store_true",
                     help="also write animation_dac.html, a replay of the DAC run")
    rep.add_argument("--jobs", type=int, choices=range(1, len(CONTROLLERS) + 1), default=1,
                     metavar="N", help="run the controllers in N processes, 1 to "
                     f"{len(CONTROLLERS)} (no progress bars above 1; default: "
                     "%(default)s)")
    rep.set_defaults(run=_reproduce)
    rpt = commands.add_parser("report", help="panels and tables of a run directory: "
                                             "one run alone, or DAC beside the "
                                             "baseline and the paper's numbers")
    rpt.add_argument("run_dir", metavar="RUN_DIR",
                     help=RUN_DIR_HELP + "; figures/, metrics.md, ablation.md and "
                                         "metrics.json are written into it")
    rpt.set_defaults(run=_report)
    ani = commands.add_parser("animate", help="self-contained HTML animation of a run "
                                              "(Meshcat)")
    ani.add_argument("run_dir", metavar="RUN_DIR", help=RUN_DIR_HELP)
    _AddController(ani, "the run to replay")
    ani.add_argument("--out", default=None, metavar="HTML",
                     help="the HTML file (default: RUN_DIR/animation_CONTROLLER.html, "
                          "with - as _, e.g. animation_model_based.html)")
    ani.set_defaults(run=_animate)
    exp = commands.add_parser("export", help="a run's logs as a CSV or Parquet table "
                                             "for pandas (one row per logged time)")
    exp.add_argument("run_dir", metavar="RUN_DIR", help=RUN_DIR_HELP)
    _AddController(exp, "the run to export")
    exp.add_argument("--format", choices=EXPORT_FORMATS, default="csv",
                     help="csv or parquet (Parquet needs pyarrow; default: "
                          "%(default)s)")
    exp.add_argument("--signals", nargs="+", default=None, metavar="NAME",
                     help="only these signals, by name (e.g. u e_tau attitude_error; "
                          "default: every named signal)")
    exp.add_argument("--out", default=None, metavar="FILE",
                     help="the table (default: RUN_DIR/logs_CONTROLLER.csv or .parquet)")
    exp.set_defaults(run=_export)
    ver = commands.add_parser(
        "verify", help="check the paper's Lyapunov claims on a DAC run (exit 1 on a "
                       "failed check)")
    ver.add_argument("target", metavar="RUN_DIR_OR_SCENARIO",
                     help="a run directory holding a DAC run, or a scenario YAML / "
                          "built-in name to simulate first (then --out is required); "
                          "verification.md, .json and .png are written beside the run")
    ver.add_argument("--out", default=None, metavar="DIR",
                     help="where to save the run of a scenario")
    _AddController(ver, "the run to verify (one with the RHS integrator)")
    ver.add_argument("--region-budget", type=float, default=300.0, metavar="SECONDS",
                     help="wall time for a planar arm's region-of-attraction "
                          "sums-of-squares program (it grows steeply with the links); "
                          "beyond it the check is reported as skipped (default: "
                          "%(default)g). Spatial arms' certificate takes milliseconds")
    ver.set_defaults(run=_verify)
    swp = commands.add_parser(
        "sweep", help="Monte Carlo sweep over uncertainty (resumes where it stopped)")
    swp.add_argument("sweep", metavar="SWEEP", help="sweep YAML (e.g. "
                                                    "sweeps/short_sweep.yaml)")
    swp.add_argument("--out", required=True, metavar="DIR",
                     help="sweep directory: rows.jsonl, summary.json, summary.md, "
                          "rows.parquet, plots; run the same command again to resume")
    swp.add_argument("--workers", type=int, default=None, metavar="N",
                     help="local worker processes (default: one per core; 0: run in "
                          "this process); with --dask local, the cluster's workers")
    swp.add_argument("--batch-size", type=int, default=None, metavar="N",
                     help="trials simulated together in one diagram (default: the "
                          "sweep's batch_size, else 64 for a planar arm, 16 for a "
                          "described arm); no trial's row depends on it")
    swp.add_argument("--dask", metavar="ADDRESS", default=None,
                     help="run on the Dask cluster at ADDRESS (e.g. tcp://host:8786), "
                          "or 'local' for a new LocalCluster")
    swp.add_argument("--report", action="store_true",
                     help="only write the summary, Parquet table and plots of the rows "
                          "so far")
    swp.set_defaults(run=_sweep)
    spa = commands.add_parser(
        "spatial", help="the former command for described arms: dacph simulate "
                        "(default scenario satellite_6dof)")
    spa.add_argument("scenario", nargs="?", default="satellite_6dof",
                     help=SCENARIO_HELP + " (default: %(default)s)")
    _AddSimulateArguments(spa)
    spa.add_argument("--panels", action="store_true",
                     help="now: dacph reproduce SCENARIO --out DIR")
    spa.set_defaults(run=_spatial)
    return parser


def main(argv: Optional[Sequence[str]] = None) -> int:
    """The ``dacph`` command line: runs the command; returns the exit status (2 for bad
    input, naming it; 130 when interrupted).

    Args:
        argv: The arguments after the program's name (default: sys.argv[1:])."""
    parser = make_parser()
    args = parser.parse_args(argv)
    if args.command is None:            # bare dacph: what it can do
        parser.print_help(sys.stderr)
        return 2
    _ShowNotes(quiet=args.quiet)
    try:
        with single_threaded():         # verify and report too (loop.threads)
            return args.run(args)
    except ConfigError as e:
        print(f"dacph: error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        # A command between its runs (a run itself saves what it has: simulate's
        # interruptible, the sweep's rows); every file it writes is replaced
        # atomically, so none is left half written.
        print(f"\ndacph: {args.command} interrupted", file=sys.stderr)
        return 130


def console_main() -> int:
    """The ``dacph`` program: main, then exit with its status (a Ctrl-C at exit ignored)."""
    status = main()
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    return status


if __name__ == "__main__":
    sys.exit(console_main())
