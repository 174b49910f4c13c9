"""The SLAM logs benchmark: a bag mapped from its file and from the CARMEN log written from it
give the same figures to within the centimetre rounding (when the logs are there)."""

import pytest

from benchmarks import slam_logs_benchmark as mut

DATA = mut.data_folder(None)


@pytest.mark.skipif(
    not (DATA / "aces.orig.bag").exists(), reason=f"the Kümmerle logs are not in {DATA}"
)
def test_a_bag_and_the_carmen_log_written_from_it_map_alike():
    bag = mut.run_one(DATA, "aces", 300)
    carmen = mut.run_one(DATA, "aces", 300, carmen=True)
    assert bag["scans"] == carmen["scans"] == 300
    assert bag["relations"] == carmen["relations"] >= 30  # those within the first 300 scans
    assert carmen["trans_mean_m"] < 0.05
    assert carmen["trans_mean_m"] == pytest.approx(bag["trans_mean_m"], abs=0.01)
