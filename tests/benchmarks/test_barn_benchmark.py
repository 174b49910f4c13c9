"""The BARN benchmark's sampling and figures; one real world driven when the arenas are there
(``slow``)."""

import pytest

from benchmarks import barn_benchmark as mut


def test_the_sample_spreads_over_the_300_worlds():
    assert mut.sample(6) == [0, 50, 100, 150, 200, 250]
    assert len(mut.sample(300)) == 300


def test_figures_count_a_success_as_reached_without_collision():
    rows = [
        dict(world=0, planner="dwa", success=True, collisions=0, time_s=50.0, real_time_factor=2.0),
        dict(
            world=1, planner="dwa", success=False, collisions=1, time_s=40.0, real_time_factor=3.0
        ),
    ]
    result = mut.figures(rows, seed=0)
    summary = {k.removeprefix("dwa_"): v for k, v in result["figures"].items()}
    assert summary["success_rate"] == 0.5 and summary["collision_rate"] == 0.5
    assert summary["median_time_s"] == 50.0 and summary["real_time_factor"] == 2.5
    assert result["tables"][0]["rows"] == rows


@pytest.mark.slow
def test_a_barn_world_is_crossed_with_no_map():
    folder = mut.barn_folder(None)
    if not (folder / "world_0.yaml").is_file():
        pytest.skip(f"no BARN worlds in {folder}")
    row = mut.run_world(folder, 0, seed=0)
    assert row["success"], row
    assert row["position_error_m"] < 0.05
