"""Executors: where episodes run. A local Ray run starts its own Ray, never a stranger's."""

import os
from pathlib import Path

import pytest

from racf.experiments.cli import main
from racf.experiments.episode import TrialSpec
from racf.experiments.sweeps.executors import executor
from racf.experiments.sweeps.run import run_episodes
from racf.experiments.sweeps.store import ResultStore


def test_an_address_without_ray_is_refused_before_any_work(tmp_path, capsys):
    with pytest.raises(ValueError, match="--backend ray"):
        next(executor("local", [TrialSpec("clean", 1, 1.5, 0)], str(tmp_path), 1, address="10.0.0.1:6379"))
    for argv in (["trials", "-n", "1"], ["sweep", "smoke.toml"], ["attack-study", "strong"], ["collect"]):
        assert main([*argv, "--address", "10.0.0.1:6379", "--out", str(tmp_path / "out")]) == 2
        assert "needs --backend ray" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()


@pytest.mark.slow
def test_a_local_ray_run_ignores_a_stale_cluster_address(tmp_path, monkeypatch):
    # A dead cluster's address, as `ray start --head` leaves behind when it dies: in the
    # environment and, where no real cluster's file is there, in Ray's address file.
    monkeypatch.setenv("RAY_ADDRESS", "127.0.0.1:6399")
    address_file = Path("/tmp/ray/ray_current_cluster")
    made = not address_file.exists()
    if made:
        address_file.parent.mkdir(parents=True, exist_ok=True)
        address_file.write_text("127.0.0.1:6399")
    try:
        specs = [TrialSpec("clean", 1, 1.5, 0)]
        rows, ran = run_episodes(specs, ResultStore(tmp_path), backend="ray", workers=1, progress=False)
    finally:
        if made:
            address_file.unlink()
    assert ran == 1 and bool(rows["success"].iloc[0])
    assert os.environ["RAY_ADDRESS"] == "127.0.0.1:6399"


def test_a_worker_whose_code_changed_refuses_to_store_under_another_id(tmp_path):
    from racf.experiments.episode import TrialSpec
    from racf.experiments.sweeps.executors import CodeChangedError, run_episode

    spec = TrialSpec("clean", 0, 1.0, 0)
    with pytest.raises(CodeChangedError, match="changed on disk while the batch ran"):
        run_episode(spec, str(tmp_path), expected_id=spec.trial_id + "x")
    assert not any(tmp_path.rglob("*.json"))


def test_a_pool_that_broke_between_two_waits_is_replaced_and_no_episode_is_lost(monkeypatch, tmp_path):
    """A worker can die after one episode finished and before the next is handed out: the pool then
    refuses the hand-out itself. The episode goes back to the queue (it never started) and a new pool
    runs it; nothing is counted as a death."""
    from concurrent.futures import Future
    from concurrent.futures.process import BrokenProcessPool

    import racf.experiments.sweeps.executors as executors

    pools = []

    class Pool:
        def __init__(self, broken: bool):
            self.broken, self.submitted = broken, []
            pools.append(self)

        def submit(self, fn, spec, out, **kw):
            if self.broken:
                raise BrokenProcessPool("a child process terminated abruptly")
            self.submitted.append(spec.trial_id)
            future = Future()
            future.set_result({"row": {"trial_id": spec.trial_id}})
            return future

        def shutdown(self, wait=True, cancel_futures=False):
            pass

    monkeypatch.setattr(executors, "spawn_pool", lambda workers: Pool(broken=not pools))
    specs = [TrialSpec("clean", 1, 1.0, seed) for seed in range(3)]
    with executors.Workers("local", 2) as workers:
        out = [r["row"]["trial_id"] for r in workers.run(specs, str(tmp_path))]
    assert sorted(out) == sorted(s.trial_id for s in specs) and len(pools) == 2 and not pools[0].submitted
