"""Fingerprints of every shipped scenario's logs, to hold a refactoring to "bit for bit"
(run: .venv/bin/python scripts/logs_fingerprint.py --out FILE [--compare OLD]).

Each scenario of scenarios/ and the built-ins (the paper's default, the short one) runs
2 s with every phase on (warm-up 0.25 s, then 0.5 s linear, 0.5 s nonlinear, 0.75 s
with the disturbance) under DAC, dac-nominal and the model-based baseline; the SHA-256 of
each log's bytes goes to FILE (JSON). --compare names every log that differs from an
earlier FILE. Compare on one machine: compiled kernels round differently on others."""
import argparse
import hashlib
import json
import logging
import sys
from pathlib import Path

from dacph_drake.scenario.built_in import short_scenario
from dacph_drake.loop.simulate import simulate
from dacph_drake.scenario import Phases, Scenario
from dacph_drake.assembly.scenario_files import load_scenario

ROOT = Path(__file__).resolve().parents[1]
CONTROLLERS = ("dac", "dac-nominal", "model-based")
DURATION = 2.0


def scenarios():
    """(name, scenario) of every shipped scenario."""
    yield "built-in default", Scenario()
    yield "built-in short", short_scenario()
    for path in sorted((ROOT / "scenarios").glob("*.yaml")):
        yield path.stem, load_scenario(path)


def fingerprints() -> dict:
    out = {}
    for name, scenario in scenarios():
        d = DURATION
        scenario.phases = Phases(warmup=d / 8, linear=d / 4, nonlinear=d / 4,
                                 disturbance=3 * d / 8)
        for controller in CONTROLLERS:
            result = simulate(scenario, controller, duration=d)
            key = f"{name}/{controller}"
            out[key] = {"status": result.status, **{
                log: hashlib.sha256(result.logs[log].tobytes()).hexdigest()[:16]
                for log in sorted(result.logs)}}
            print(key, result.status, flush=True)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, required=True)
    parser.add_argument("--compare", type=Path, default=None)
    args = parser.parse_args()
    logging.disable(logging.WARNING)
    prints = fingerprints()
    args.out.write_text(json.dumps(prints, indent=1, sort_keys=True) + "\n")
    if args.compare is None:
        return
    old = json.loads(args.compare.read_text())
    differ = [f"{run}: {log}" for run in sorted(set(old) | set(prints))
              for log in sorted(set(old.get(run, {})) | set(prints.get(run, {})))
              if old.get(run, {}).get(log) != prints.get(run, {}).get(log)]
    print(f"{len(prints)} runs; {len(differ)} logs differ" +
          "".join(f"\n  {line}" for line in differ))
    sys.exit(1 if differ else 0)


if __name__ == "__main__":
    main()
