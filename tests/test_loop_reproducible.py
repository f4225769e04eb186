"""results/loop is reproducible: the loop run again on x-io short_walk gives the committed attribution, also with
its simulations on two worker processes (the committed one ran on one)."""

import json
import warnings
from pathlib import Path

import pytest

from conftest import DATA, needs_data
from gaitsim.loop import attribution
from gaitsim.measured import load_dataset

pytestmark = needs_data("xio-ngimu")
COMMITTED = Path(__file__).resolve().parents[1] / "results" / "loop" / "xio-ngimu" / "short_walk" / "attribution.json"


def test_short_walk_attribution_matches_the_committed_one():
    committed = json.loads(COMMITTED.read_text())
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # the loader's data-quality counts are in meta
        rec = {r.meta["recording"]: r for r in load_dataset("xio-ngimu", DATA)}["short_walk"]
    result = attribution.run_loop(rec, workers=2)
    assert [(a["residual"], a["effect"]) for a in result.attributions] == [
        (a["residual"], a["effect"]) for a in committed["attributions"]]
    for now, then in zip(result.attributions, committed["attributions"]):
        assert now["residual_before"] == pytest.approx(then["residual_before"], rel=1e-6, abs=1e-9)
        if then["magnitude"] is not None:
            assert now["magnitude"] == pytest.approx(then["magnitude"], rel=1e-6, abs=1e-9)
