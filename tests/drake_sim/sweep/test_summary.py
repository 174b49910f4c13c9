import pytest

from drake_sim.sweep import summary as mut


def test_wilson_interval():
    # Reference values (e.g. statsmodels proportion_confint(method="wilson")).
    assert mut.wilson_interval(8, 10) == pytest.approx((0.4902, 0.9433), abs=1e-4)
    assert mut.wilson_interval(0, 10) == pytest.approx((0.0, 0.2775), abs=1e-4)
    assert mut.wilson_interval(10, 10) == pytest.approx((0.7225, 1.0), abs=1e-4)
    assert mut.wilson_interval(0, 0) == (0.0, 1.0)


def test_wilson_interval_holds_the_rate():
    for n in range(1, 60):
        for k in range(n + 1):
            low, high = mut.wilson_interval(k, n)
            assert 0.0 <= low <= k / n <= high <= 1.0, (k, n)


def test_numeric():
    assert mut.numeric([1, 2.5, True, None, "x", float("nan"), [1]]) == [1.0, 2.5, 1.0]


def test_summarize_and_format():
    rows = [
        {"status": "ok", "success": True, "m": 1.0},
        {"status": "ok", "success": False, "m": 3.0},
        {"status": "ok", "success": True, "m": 2.0},
        {"status": "failed", "success": False, "m": None},
    ]
    dut = mut.summarize(rows, ["m", "absent"], has_success=True)
    assert (dut["rollouts"], dut["ok"], dut["failed"]) == (4, 3, 1)
    assert dut["success"]["count"] == 2 and dut["success"]["rate"] == 0.5
    assert dut["success"]["ci95"] == pytest.approx(mut.wilson_interval(2, 4))
    assert dut["metrics"] == {"m": {"median": 2.0, "min": 1.0, "max": 3.0, "n": 3}}
    text = mut.format_summary(dut)
    assert "rollouts 4 (ok 3, failed 1)" in text
    assert "success 2/4 = 50.0% (Wilson 95% CI 15.0% to 85.0%)" in text
    assert "m: median 2, min 1, max 3" in text
    assert "success" not in mut.summarize(rows, ["m"], has_success=False)
