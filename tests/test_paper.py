"""The full paper reproduction (1500 s, all three controllers): a long test, run with
`pytest --long`. It asserts what must hold for the reproduction to stand, and
prints the table; the paper's targets are quoted in the issue notes with the
measured numbers (met or missed)."""
import json

import pytest

from dacph_drake.app.reproduce import reproduce
from dacph_drake.scenario.built_in import paper_scenario


@pytest.mark.long
def test_paper_reproduction(tmp_path):
    summary = reproduce(paper_scenario(), tmp_path, progress=False, jobs=2)
    print(json.dumps(summary["table"], indent=1))
    assert all(run["status"] == "ok" for run in summary["runs"].values())
    rows = {row["key"]: row["this_project"] for row in summary["table"]}
    # DAC beats the baseline on tracking (the paper's headline claim).
    assert rows["tracking_error_reduction"] > 0
    assert rows["dac.min_clearance"] > 0 and rows["dac.c_min_over_bound"] >= 1.0
    for figure in summary["figures"]:
        assert (tmp_path / figure).stat().st_size > 10_000
    # Learning beats the nominal prior in every phase; the integrator's checks
    # reject at most 1 % of the learned estimates.
    dac = summary["metrics"]["dac"]
    for phase in ("phase1", "phase2", "phase3"):
        assert dac[f"{phase}.B_error_ratio"] <= 1.0 and dac[f"{phase}.D_error_ratio"] <= 1.0
        assert dac[f"{phase}.rejected_share"] <= 0.01
