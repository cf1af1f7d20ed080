"""A service that lies: it speaks protocol 2 and answers the car's own depth distance (as the raw
defence would) for its first ``honest`` estimates, then the answer it is told to give. The car's
tests use it to send what ``racf serve`` never would."""

from __future__ import annotations

import math
import threading

import zmq

from racf.experiments.link.wire import PROTOCOL, decode_sample, pack, unpack

__all__ = ["FakeService", "LIES", "IN_RANGE_LIES"]

#: What a lying service can answer an estimate with, by name: a function of the request id and the
#: honest answer to the map it sends.
LIES = {
    "nan": lambda rid, honest: {**honest, "distance": math.nan},
    "negative": lambda rid, honest: {**honest, "distance": -1.0},
    "inf": lambda rid, honest: {**honest, "distance": math.inf},
    "far": lambda rid, honest: {**honest, "distance": 1e9},
    "string": lambda rid, honest: {**honest, "distance": "near"},
    "error": lambda rid, honest: {"id": rid, "error": "the defence is on strike"},
    "stale": lambda rid, honest: {**honest, "id": rid - 1},
    "no id": lambda rid, honest: {k: v for k, v in honest.items() if k != "id"},
    "bool": lambda rid, honest: {**honest, "distance": True},
    "stands text": lambda rid, honest: {**honest, "stands": "yes"},
    "no distance": lambda rid, honest: {k: v for k, v in honest.items() if k != "distance"},
    "diagnostics list": lambda rid, honest: {**honest, "diagnostics": [1, 2]},
    "not a map": None,  # the bytes of a msgpack list
}

#: Lies the protocol's check cannot see: a distance in range, the ids kept (issue 78). The car's own
#: witnesses must outvote them.
IN_RANGE_LIES = {
    "always 4 m": lambda rid, honest: {**honest, "distance": 4.0, "stands": False},
    "3 m farther": lambda rid, honest: {**honest, "distance": None if honest["distance"] is None
                                        else honest["distance"] + 3.0, "stands": False},
    "nothing stands": lambda rid, honest: {**honest, "distance": None, "stands": False},
}
LIES.update(IN_RANGE_LIES)


class FakeService:
    """A ROUTER on a free loopback port, in a daemon thread, until :meth:`stop`.

    Args:
        lie: a key of LIES (None: always honest), or a function (request id, honest answer) -> answer.
        honest: estimates answered honestly before the lies begin.
        hellos: a function (the hello's number, from 1; its honest answer) -> the answer, or None
            for no answer at all (None: every hello answered honestly).
        pong: the answer to a ping (None: protocol 2's).
        ping_delay_s: how long the service takes to answer a ping (a loaded one).
    """

    def __init__(self, lie=None, honest: int = 30, hellos=None, pong: dict | None = None,
                 ping_delay_s: float = 0.0, port: int | None = None) -> None:
        self.ping_delay_s = ping_delay_s
        self.lie = LIES[lie] if isinstance(lie, str) else lie
        self.hello_answer, self.pong = hellos, pong
        self.raw_lie = lie == "not a map"
        self.honest, self.estimates, self.lies, self.hellos = honest, 0, 0, 0
        self._stop = threading.Event()
        ctx = zmq.Context.instance()
        self._sock = ctx.socket(zmq.ROUTER)
        self._sock.setsockopt(zmq.LINGER, 0)
        if port is None:
            port = self._sock.bind_to_random_port("tcp://127.0.0.1")
        else:
            self._sock.bind(f"tcp://127.0.0.1:{port}")
        self.endpoint = f"tcp://127.0.0.1:{port}"
        self._thread = threading.Thread(target=self._serve, daemon=True)
        self._thread.start()

    def _serve(self) -> None:
        while not self._stop.is_set():
            if not self._sock.poll(20):
                continue
            identity, _, raw = self._sock.recv_multipart()
            answer = self._answer(unpack(raw))
            if answer is not None:
                self._sock.send_multipart([identity, b"", answer])

    def _answer(self, message: dict) -> bytes | None:
        op, rid = message["op"], message.get("id")
        if op == "ping":
            self._stop.wait(self.ping_delay_s)
            return pack(self.pong if self.pong is not None else {"pong": True, "protocol": PROTOCOL, "id": rid})
        if op == "hello":
            self.hellos += 1
            honest = {"estimator": message["estimator"], "options": {}, "protocol": PROTOCOL, "id": rid}
            answer = honest if self.hello_answer is None else self.hello_answer(self.hellos, honest)
            return None if answer is None else pack(answer)
        if op != "estimate":
            return pack({"id": rid})
        self.estimates += 1
        d = decode_sample(message["sample"]).d_meas
        honest = {"id": rid, "distance": None if math.isnan(d) else d, "stands": None, "diagnostics": {}}
        if self.lie is None and not self.raw_lie or self.estimates <= self.honest:
            return pack(honest)
        self.lies += 1
        if self.raw_lie:
            import msgpack

            return msgpack.packb([1, 2, 3])
        return pack(self.lie(rid, honest))

    def stop(self) -> None:
        self._stop.set()
        self._thread.join(5)
        self._sock.close(0)

    def __enter__(self) -> "FakeService":
        return self

    def __exit__(self, *exc) -> None:
        self.stop()


def main() -> None:
    """Prints, for each lie from the 31st estimate on, what became of the episode (sign 1, 1 m/s, seed 3)
    beside the car's own depth fallback: `python -m tests.experiments.link.fake_service`."""
    from dataclasses import replace

    from racf.experiments.episode import TrialSpec, run_trial

    spec = TrialSpec("clean", 1, 1.0, 3)
    own, _ = run_trial(spec)

    def outcome(result) -> dict:
        return {k: v for k, v in result.to_dict().items() if not k.startswith(("service", "trial_id"))}

    print(f"{'lie':<9}{'completed':>10}{'lies':>6}{'service_invalid':>17}{'fallback steps':>16}{'late steps':>12}"
          f"{'outcome = own depth':>21}")
    for lie in ("nan", "negative", "inf", "far", "string", "error", "stale"):
        with FakeService(lie, honest=30) as fake:
            result, _ = run_trial(replace(spec, estimator_endpoint=fake.endpoint, estimator_timeout_ms=5000.0))
            lies = fake.lies
        row = result.to_dict()
        print(f"{lie:<9}{'yes':>10}{lies:>6}{row['service_invalid']:>17}{row['service_fallback_steps']:>16}"
              f"{row['service_late_steps']:>12}{str(outcome(result) == outcome(own)):>21}")
    print(f"the car's own depth (raw, in process): success {own.success}, failure {own.failure}")


if __name__ == "__main__":
    import logging

    logging.disable(logging.WARNING)
    main()
