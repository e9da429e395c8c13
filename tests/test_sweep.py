"""Monte Carlo sweeps (dacph sweep): the same rows on any executor, resuming after a
kill, failed trials recorded with their reason, clear errors for bad sweep files."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet
import pytest

from dacph_drake.app.cli import main
from dacph_drake.scenario.errors import ConfigError
from dacph_drake.montecarlo.definition import load_sweep
from dacph_drake.montecarlo.executors import InProcessExecutor, dask_executor
from dacph_drake.montecarlo.runner import run_sweep
from dacph_drake.montecarlo.store import ROWS, RowStore, read_rows, sorted_rows
from dacph_drake.montecarlo.summary import write_summary
from dacph_drake.scenario.planar_arm import LinkParams, link_inertia_bound
from dacph_drake.scenario import Phases
from dacph_drake.scenario.built_in import short_scenario
from dacph_drake.assembly.scenario_files import load_scenario, save_scenario

SWEEPS = Path(__file__).resolve().parents[1] / "sweeps"
TRIALS = 4
SWEEP = f"""\
scenario: tiny.yaml
trials: {TRIALS}
seed: 11
controllers: [dac, model-based]
distributions:
  link_mass_scale: !Uniform {{min: 0.9, max: 1.1}}
  link_length_scale: !GaussianVector {{mean: [1.0, 1.0], stddev: [0.02]}}
  delta_B_scale: !Uniform {{min: 0.5, max: 1.5}}
  delta_D_scale: !UniformDiscrete {{values: [0.5, 1.0, 2.0]}}
  disturbance_frequency_scale: !Uniform {{min: 0.8, max: 1.2}}
  q0: !UniformVector {{min: [0.2, 0.8], max: [0.4, 1.2]}}
"""


def write_sweep(folder: Path, text: str, name: str = "sweep.yaml") -> Path:
    """The sweep file and, beside it, tiny.yaml: the short scenario cut to 1.1 s."""
    folder.mkdir(parents=True, exist_ok=True)
    scenario = short_scenario()
    scenario.phases = Phases(warmup=0.2, linear=0.3, nonlinear=0.3, disturbance=0.3)
    save_scenario(scenario, folder / "tiny.yaml")
    (folder / name).write_text(text)
    return folder / name


def comparable(rows):
    """Rows without their wall times, as JSON text (NaN-safe, bitwise)."""
    def strip(value):
        if isinstance(value, dict):
            return {k: strip(v) for k, v in value.items() if k != "wall_time"}
        return value
    return [json.dumps(strip(r), sort_keys=True) for r in rows]


@pytest.fixture(scope="module")
def serial(tmp_path_factory):
    """The sweep run in this process: (sweep file, output directory, rows)."""
    folder = tmp_path_factory.mktemp("serial")
    path = write_sweep(folder, SWEEP)
    rows = run_sweep(load_sweep(path), folder / "out", InProcessExecutor(), 1)
    return path, folder / "out", rows


def test_serial_sweep_runs_every_trial(serial):
    _, out, rows = serial
    assert [r["trial"] for r in rows] == list(range(TRIALS))
    assert all(r["status"] == "ok" for r in rows), [r["reason"] for r in rows]
    assert len((out / ROWS).read_text().splitlines()) == TRIALS
    samples = [r["sampled"]["link_mass_scale"] for r in rows]
    assert len({tuple(s) for s in samples}) == TRIALS      # each trial its own sample
    assert all(0.9 <= f <= 1.1 for s in samples for f in s)
    manifest = json.loads((out / "manifest.json").read_text())
    assert manifest["sessions"][0]["versions"]["drake"]


def test_process_pool_gives_identical_rows(serial, tmp_path):
    path, _, rows = serial
    pooled = run_sweep(load_sweep(path), tmp_path / "out", slots=2)
    assert comparable(pooled) == comparable(rows)


def test_a_local_pool_is_joined_before_the_sweep_returns(serial, tmp_path):
    """No pool thread is left for the interpreter's exit to join: a Ctrl-C there
    would end in a threading traceback and exit 0."""
    import threading
    path, _, rows = serial
    before = set(threading.enumerate())
    pooled = run_sweep(load_sweep(path), tmp_path / "out", slots=1)
    assert comparable(pooled) == comparable(rows)
    left = [t for t in threading.enumerate() if t not in before and not t.daemon]
    assert left == [], left


def test_a_trials_row_is_the_same_whatever_batch_it_lands_in(serial, tmp_path):
    """The serial sweep ran its 4 trials as one batch (one diagram per controller);
    one trial per diagram gives the same rows, and so does a batch_size in the
    sweep file, which leaves the sweep's fingerprint as it was."""
    path, _, rows = serial
    alone = run_sweep(load_sweep(path), tmp_path / "alone", InProcessExecutor(), 1,
                      batch_size=1)
    assert comparable(alone) == comparable(rows)
    sized = write_sweep(tmp_path / "sized", SWEEP + "batch_size: 3\n")
    assert load_sweep(sized).fingerprint() == load_sweep(path).fingerprint()
    assert comparable(run_sweep(load_sweep(sized), tmp_path / "sized" / "out",
                                InProcessExecutor(), 1)) == comparable(rows)


def test_dask_local_cluster_gives_identical_rows(serial, tmp_path):
    path, _, rows = serial
    with dask_executor("local", 2) as (executor, slots):
        assert slots == 2
        on_dask = run_sweep(load_sweep(path), tmp_path / "out", executor, slots)
    assert comparable(on_dask) == comparable(rows)


def _spawned_workers(pid: int):
    """Process-pool workers started by ``pid``."""
    children = Path(f"/proc/{pid}/task/{pid}/children").read_text().split()
    workers = []
    for child in children:
        try:
            if b"spawn_main" in Path(f"/proc/{child}/cmdline").read_bytes():
                workers.append(int(child))
        except FileNotFoundError:
            pass
    return workers


def _alive(pid: int) -> bool:
    try:
        return Path(f"/proc/{pid}/stat").read_text().split()[2] != "Z"
    except FileNotFoundError:
        return False


def _start_cli_sweep(path: Path, out: Path, workers: int, batch_size: int
                     ) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "dacph_drake.app.cli", "sweep", str(path),
                             "--out", str(out), "--workers", str(workers),
                             "--batch-size", str(batch_size)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE)


def _wait_for_rows(out: Path, process: subprocess.Popen, timeout: float = 60.0) -> None:
    deadline = time.monotonic() + timeout
    while not ((out / ROWS).exists() and (out / ROWS).read_text().count("\n") >= 1):
        assert process.poll() is None, process.communicate()
        assert time.monotonic() < deadline, "no row appeared"
        time.sleep(0.05)


def _cli_sweep_with_a_first_row(path: Path, out: Path, workers: int = 2,
                                batch_size: int = 1):
    """A CLI sweep, once its first row is saved: (process, worker pids)."""
    process = _start_cli_sweep(path, out, workers, batch_size)
    _wait_for_rows(out, process)
    return process, _spawned_workers(process.pid)


@pytest.mark.parametrize("workers, batch_size", [(2, 1), (1, 2)])
def test_sweep_killed_with_sigkill_resumes_without_loss_or_duplicates(
        serial, tmp_path, workers, batch_size):
    """Killed once its first rows are saved (one trial per diagram on 2 workers, or
    batches of 2 on one worker: killed during the second batch), the sweep resumes
    with the trials not saved, none twice, and the rows of an uninterrupted run."""
    path, _, rows = serial
    out = tmp_path / "out"
    process, workers = _cli_sweep_with_a_first_row(path, out, workers, batch_size)
    process.send_signal(signal.SIGKILL)
    process.communicate()
    finished = len(read_rows(out))
    assert 1 <= finished < TRIALS            # killed in the middle
    deadline = time.monotonic() + 10
    while any(_alive(w) for w in workers) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert workers and not any(_alive(w) for w in workers)   # died with their parent
    with open(out / ROWS, "a") as f:         # a row cut short by the kill
        f.write('{"trial": 3, "status": "o')
    resumed = subprocess.run([sys.executable, "-m", "dacph_drake.app.cli", "sweep", str(path),
                              "--out", str(out)], capture_output=True, text=True)
    assert resumed.returncode == 0, resumed.stderr
    assert f"resuming: {finished} of {TRIALS} trials already done" in resumed.stderr
    lines = (out / ROWS).read_text().splitlines()
    assert sorted(json.loads(line)["trial"] for line in lines) == list(range(TRIALS))
    assert comparable(sorted_rows(read_rows(out))) == comparable(rows)


def test_killed_worker_is_replaced_and_its_trial_rerun(serial, tmp_path):
    path, _, rows = serial
    out = tmp_path / "out"
    process, workers = _cli_sweep_with_a_first_row(path, out)
    os.kill(workers[0], signal.SIGKILL)
    _, stderr = process.communicate(timeout=120)
    assert process.returncode == 0, stderr
    assert b"a worker process died: trials" in stderr
    assert comparable(sorted_rows(read_rows(out))) == comparable(rows)


def test_failed_trials_are_recorded_with_their_reason_and_the_sweep_goes_on(tmp_path):
    # Two documented ways to fail: a link inertia scaled beyond the physical bound
    # (the sampled scenario is invalid), and a disturbance 10^4 times the nominal
    # one (the divergence monitor stops the run).
    path = write_sweep(tmp_path, """\
scenario: tiny.yaml
trials: 8
seed: 3
controllers: [model-based]
distributions:
  link_inertia_scale: !UniformVector {min: [1.0, 1.0], max: [1.0, 4.0]}
  disturbance_scale: !UniformDiscrete {values: [1.0, 1.0e4]}
""")
    definition = load_sweep(path)
    rows = run_sweep(definition, tmp_path / "out", InProcessExecutor(), 1)
    assert [r["trial"] for r in rows] == list(range(8))
    link = LinkParams()
    largest_scale = link_inertia_bound(link) / link.inertia
    kinds = set()
    for row in rows:
        invalid = [k for k, f in enumerate(row["sampled"]["link_inertia_scale"])
                   if f > largest_scale]
        if invalid:
            kinds.add("invalid")
            assert row["status"] == "failed" and row["runs"] == {}
            assert row["reason"].startswith(
                f"invalid sample: robot.truth.links[{invalid[0]}].inertia = ")
            assert "rod bound" in row["reason"]
        elif row["sampled"]["disturbance_scale"] > 1:
            kinds.add("diverged")
            run = row["runs"]["model-based"]
            assert row["status"] == "failed" and run["status"] == "diverged"
            assert run["final_time"] < 1.1 and "exceeded 50" in run["reason"]
            assert run["reason"] in row["reason"]
        else:
            kinds.add("ok")
            assert row["status"] == "ok" and row["reason"] == ""
    assert kinds == {"invalid", "diverged", "ok"}
    summary = write_summary(tmp_path / "out", definition)
    assert summary["succeeded"] == sum(r["status"] == "ok" for r in rows)
    assert [f["trial"] for f in summary["failures"]] == \
        [r["trial"] for r in rows if r["status"] != "ok"]


def test_summary_table_parquet_and_plots(serial):
    path, out, rows = serial
    summary = write_summary(out, load_sweep(path))
    table = pyarrow.parquet.read_table(out / "rows.parquet").to_pylist()
    assert [r["trial"] for r in table] == list(range(TRIALS))
    assert [r["sampled.q0[1]"] for r in table] == [r["sampled"]["q0"][1] for r in rows]
    assert [r["dac.tracking_error_rms"] for r in table] == \
        [r["runs"]["dac"]["metrics"]["tracking_error_rms"] for r in rows]
    e = {c: np.array([r["runs"][c]["metrics"]["tracking_error_rms"] for r in rows])
         for c in ("dac", "model-based")}
    paired = summary["paired"]["tracking_error_reduction"]
    assert paired["n"] == TRIALS
    assert paired["mean"] == pytest.approx(np.mean(1 - e["dac"] / e["model-based"]),
                                           rel=1e-12)
    low, high = paired["ci95"]
    assert low <= paired["mean"] <= high and low < high
    quantiles = summary["controllers"]["dac"]["metrics"]["tracking_error_rms"]
    assert quantiles["q50"] == pytest.approx(np.median(e["dac"]), rel=1e-12)
    assert quantiles["q05"] <= quantiles["q25"] <= quantiles["q50"] <= \
        quantiles["q75"] <= quantiles["q95"]
    assert summary["controllers"]["model-based"]["success_rate"] == 1.0
    for figure in summary["figures"]:
        assert (out / figure).stat().st_size > 10_000
    assert "| DAC vs model-based, paired |" in (out / "summary.md").read_text()


def test_summary_learning_section(serial):
    """Per phase: the share of trials whose learned B and D beat the prior and the
    ratios' median, from the rows' own metrics."""
    path, out, rows = serial
    summary = write_summary(out, load_sweep(path))
    learning = summary["learning"]
    assert learning["trials"] == TRIALS
    for phase in ("phase1", "phase2", "phase3"):
        for name in ("B", "D"):
            ratios = np.array([r["runs"]["dac"]["metrics"][f"{phase}.{name}_error_ratio"]
                               for r in rows])
            entry = learning["phases"][phase][name]
            assert entry["beats_prior"] == pytest.approx(np.mean(ratios <= 1.0))
            assert entry["median"] == pytest.approx(np.median(ratios), rel=1e-12)
        assert learning["phases"][phase]["e_tau_ratio_median"] is None   # no dac-nominal
    assert "Learning (DAC, 4 finished trials)" in (out / "summary.md").read_text()


def test_shipped_learning_robustness_sweep_loads():
    definition = load_sweep(SWEEPS / "learning_robustness.yaml")
    assert definition.scenario == short_scenario()
    assert definition.sweep.trials >= 20 and definition.sweep.distributions.learner_seed \
        is None                                # each trial seeds its own learner
    assert definition.sweep.controllers == ["dac", "dac-nominal"]


def test_an_output_directory_belongs_to_one_sweep(tmp_path):
    first = load_sweep(write_sweep(tmp_path, SWEEP))
    other = load_sweep(write_sweep(tmp_path, SWEEP.replace("seed: 11", "seed: 12"),
                                   "other.yaml"))
    store = RowStore(tmp_path / "out", first, {}, "test")
    with pytest.raises(ConfigError, match="is in use by another running sweep"):
        RowStore(tmp_path / "out", first, {}, "test")
    store.close()
    with pytest.raises(ConfigError, match=r"holds a different sweep .*allowed: the sweep "
                                          r"that created it, or a new output directory"):
        RowStore(tmp_path / "out", other, {}, "test")
    RowStore(tmp_path / "out", first, {}, "test").close()      # the same one resumes


def test_a_sensing_sweep_samples_the_sensors_and_groups_its_batches(tmp_path,
                                                                    monkeypatch):
    """Sensing samples (noise scale, command delay, actuator lag) reach each trial's
    sensing section; trials of different sensing share no diagram, those of equal
    sensing do, and every row is the one the trial gets alone; with verify: true each
    DAC run carries verify's verdict."""
    from dacph_drake.montecarlo.definition import sample_trial
    from dacph_drake.scenario.built_in import spacecraft_sensing
    folder = tmp_path / "sensing"
    write_sweep(folder, "")
    scenario = load_scenario(folder / "tiny.yaml")
    scenario.sensing = spacecraft_sensing()
    save_scenario(scenario, folder / "tiny.yaml")
    path = folder / "sweep.yaml"
    path.write_text("scenario: tiny.yaml\ntrials: 4\nseed: 3\n"
                    "controllers: [dac, model-based]\nverify: true\n"
                    "distributions:\n"
                    "  sensing_noise_scale: !UniformDiscrete {values: [0.0, 2.0]}\n"
                    "  sensing_rhs_delay: !UniformDiscrete {values: [1, 2]}\n"
                    "  sensing_actuator_lag: !Deterministic {value: 0.0005}\n")
    definition = load_sweep(path)
    for trial in range(4):
        sample = sample_trial(definition, trial)
        sensing = sample.scenario.sensing
        assert sensing.rhs_delay == sample.sampled["sensing_rhs_delay"] in (1, 2)
        assert sensing.actuator_lag == 0.0005
        assert sensing.gyro_noise == (sample.sampled["sensing_noise_scale"]
                                      * spacecraft_sensing().gyro_noise)
    import dacph_drake.loop.simulate as simulate_module
    diagrams, simulate_batch = [], simulate_module.simulate_batch

    def counted(scenarios, *args, **kwargs):
        diagrams.append(sorted((s.sensing.rhs_delay, s.sensing.gyro_noise)
                               for s in scenarios))
        return simulate_batch(scenarios, *args, **kwargs)
    monkeypatch.setattr(simulate_module, "simulate_batch", counted)
    batched = run_sweep(definition, folder / "batched", InProcessExecutor(), 1)
    assert all(r["status"] == "ok" for r in batched), [r["reason"] for r in batched]
    groups = {(sample_trial(definition, t).scenario.sensing.rhs_delay,
               sample_trial(definition, t).scenario.sensing.gyro_noise) for t in range(4)}
    assert len(diagrams) == 2 * len(groups) and all(len(set(d)) == 1 for d in diagrams)
    # verify: true: each DAC run carries dacph verify's verdict and its delay margin,
    # at least the delay it ran with; the baseline has no RHS loop to verify.
    for row in batched:
        verdict = row["runs"]["dac"]["verify"]
        assert isinstance(verdict["ok"], bool) and "lhs_envelope" not in verdict["failed"]
        assert verdict["delay_tolerance"]["in_the_run"] == row["sampled"]["sensing_rhs_delay"]
        assert "verify" not in row["runs"]["model-based"]
    alone = run_sweep(definition, folder / "alone", InProcessExecutor(), 1, batch_size=1)
    assert comparable(alone) == comparable(batched)


def test_shipped_sweep_loads():
    definition = load_sweep(SWEEPS / "short_sweep.yaml")
    assert definition.scenario == short_scenario()
    assert definition.sweep.controllers == ["dac", "model-based"]


@pytest.mark.parametrize("setting, message", [
    ("trails: 3\n", r"unknown key 'trails'; allowed: scenario, trials, seed, controllers"),
    ("distributions: {link_mas_scale: 1.0}\n",
     r"unknown key 'link_mas_scale'; allowed: link_mass_scale, link_length_scale"),
    ("distributions: {link_mass_scale: !Triangular {min: 1.0}}\n",
     r"distributions.link_mass_scale: !Triangular is not a distribution here; allowed: "
     r"!Deterministic, !Gaussian, !Uniform, !UniformDiscrete, !DeterministicVector"),
    ("distributions: {delta_D_scale: !UniformVector {min: [1.0], max: [2.0]}}\n",
     r"delta_D_scale: !UniformVector is not a distribution here; allowed: "
     r"!Deterministic, !Gaussian, !Uniform, !UniformDiscrete$"),
    ("distributions: {delta_D_scale: !Uniform {min: 1.0, maxx: 2.0}}\n",
     r"distributions.delta_D_scale: unknown key 'maxx' of !Uniform; allowed: min, max"),
    ("distributions: {delta_B_scale: !Uniform {min: 1.2, max: 0.8}}\n",
     r"distributions.delta_B_scale: !Uniform min = 1.2 > max = 0.8; allowed: min <= max"),
    ("distributions: {disturbance_scale: !Gaussian {mean: 1.0, stddev: -0.1}}\n",
     r"distributions.disturbance_scale: !Gaussian stddev = -0.1; allowed: >= 0"),
    ("distributions: {q0: !UniformVector {min: [0.1], max: [0.2]}}\n",
     r"distributions.q0: min has 1 entries; allowed: 2 \(one per link\)"),
    ("distributions: {learner_seed: !UniformDiscrete {values: [1, 2.5]}}\n",
     r"distributions.learner_seed = 2.5; allowed: integers >= 0"),
    ("trials: 0\n", r"trials = 0 is out of range; allowed: in \[1, 1e\+06\]"),
    ("batch_size: -1\n", r"batch_size = -1 is out of range; allowed: in \[0, 4096\]"),
    ("controllers: [dac, pid]\n", r"controllers: 'pid' is unknown; allowed: dac, dac-nominal, model-based"),
    ("scenario: missing.yaml\n", r"scenario = 'missing.yaml' is neither a built-in scenario"),
    ("distributions: {sensing_noise_scale: 2.0}\n",
     r"distributions.sensing_noise_scale samples the base scenario's sensing, which is "
     r"off; allowed: a base scenario with sensing.enabled: true"),
])
def test_malformed_sweep_is_named(tmp_path, setting, message):
    path = write_sweep(tmp_path, setting)
    with pytest.raises(ConfigError, match=message):
        load_sweep(path)


def test_cli_reports_a_malformed_sweep(tmp_path, capsys):
    path = write_sweep(tmp_path, "trials: -2\n")
    assert main(["sweep", str(path), "--out", str(tmp_path / "out")]) == 2
    assert "trials = -2 is out of range" in capsys.readouterr().err
    path = write_sweep(tmp_path, SWEEP)
    assert main(["sweep", str(path), "--out", str(tmp_path / "out"),
                 "--batch-size", "0"]) == 2
    err = capsys.readouterr().err
    assert "--batch-size = 0; allowed: 1 to 4096" in err and len(err.splitlines()) == 1
    with pytest.raises(ConfigError, match=r"batch_size = 0 is out of range"):
        run_sweep(load_sweep(path), tmp_path / "api", InProcessExecutor(), 1, batch_size=0)


def test_a_sweep_with_no_successful_trial_exits_1(tmp_path, capsys):
    """Every sample invalid (link 2 inertia far above the rod bound): each trial is
    recorded as failed with its reason, which names a plain number, and the command
    says so and exits 1."""
    path = write_sweep(tmp_path, """\
scenario: tiny.yaml
trials: 3
seed: 5
controllers: [model-based]
distributions:
  link_inertia_scale: !UniformVector {min: [1.0, 50.0], max: [1.0, 60.0]}
""")
    out = tmp_path / "out"
    assert main(["sweep", str(path), "--out", str(out), "--workers", "0"]) == 1
    assert "none of the 3 trials ran to the end" in capsys.readouterr().err
    rows = [json.loads(line) for line in (out / "rows.jsonl").read_text().splitlines()]
    assert len(rows) == 3 and all(r["status"] == "failed" for r in rows)
    assert all("robot.truth.links[1].inertia = " in r["reason"] and "np.float64" not in r["reason"]
               for r in rows)


def test_a_base_scenario_that_cannot_run_fails_every_trial_with_the_reason(tmp_path):
    """The base scenario loads but starts the arm inside the base (refused when each
    trial's diagram is built): every trial is recorded as failed, naming q0, and the
    sweep goes through all of them."""
    path = write_sweep(tmp_path, """\
scenario: tiny.yaml
trials: 3
seed: 2
controllers: [model-based, dac]
distributions:
  disturbance_scale: !Uniform {min: 0.5, max: 1.5}
""")
    scenario = load_scenario(tmp_path / "tiny.yaml")
    scenario.q0 = [2.5, 0.5]
    save_scenario(scenario, tmp_path / "tiny.yaml")
    rows = run_sweep(load_sweep(path), tmp_path / "out", InProcessExecutor(), 1)
    assert [r["trial"] for r in rows] == [0, 1, 2]
    assert all(r["status"] == "failed" and "puts the arm into the base" in r["reason"]
               for r in rows)
