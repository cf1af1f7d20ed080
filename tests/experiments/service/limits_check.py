"""What must hold of `racf serve --max-sessions 8 --sessions-per-client 4 --idle-s 5`, with those very
flags (tests/experiments/service/test_limits.py checks the same with a 1 s idle, to stay quick):

    python -m tests.experiments.service.limits_check
"""
import subprocess
import sys
import threading
import time

import zmq
from racf.experiments.link.wire import PROTOCOL, pack, unpack
from racf.experiments.link.remote import RemoteEstimator
from racf.controllers import PerceptionSample


def main() -> None:
    proc = subprocess.Popen([sys.executable, "-m", "racf.experiments.cli", "serve", "--defence", "raw", "--bind", "tcp://127.0.0.1:0",
                             "--max-sessions", "8", "--sessions-per-client", "4", "--idle-s", "5"], stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL, text=True)
    endpoint = proc.stdout.readline().split("listening at ", 1)[1].split()[0]
    hp = endpoint.split("://")[1]

    def hello(src=None):
        s = zmq.Context.instance().socket(zmq.REQ); s.setsockopt(zmq.LINGER, 0)
        s.connect(f"tcp://{src}:0;{hp}" if src else endpoint)
        s.send(pack({"op": "hello", "id": 1, "protocol": PROTOCOL, "estimator": "raw", "options": {}}))
        assert s.poll(5000)
        return s, unpack(s.recv())

    def ask(s):
        s.send(pack({"op": "reset", "id": 2})); assert s.poll(5000); return unpack(s.recv())

    try:
        opened = [hello() for _ in range(10)]
        granted = [s for s, a in opened if "refused" not in a]
        print(f"hellos from one address granted: {len(granted)} of 10")
        time.sleep(8)
        answering = sum("error" not in ask(s) for s in granted)
        print(f"sessions answering after 8 s idle: {answering} of {len(granted)}")
        for s, _ in opened: s.close(0)
        time.sleep(0.3)
        many = [hello(f"127.0.0.{k + 2}") for k in range(64)]
        print(f"64 loopback addresses: {sum('refused' not in a for _, a in many)} granted (total cap 8)")
        for s, _ in many: s.close(0)
        t0 = time.monotonic()
        while True:
            s, a = hello("127.0.0.99"); s.close(0)
            if "refused" not in a: break
            time.sleep(0.05)
        print(f"a new car got a session {time.monotonic() - t0:.2f} s after the 64 closed their sockets")
        time.sleep(0.3)
        stop = threading.Event(); cycled = [0]
        def cycle():
            held = []
            while not stop.is_set():
                held.append(hello()[0]); cycled[0] += 1
                if len(held) == 6:
                    for s in held: s.close(0)
                    held = []; time.sleep(0.05)
            for s in held: s.close(0)
        car = RemoteEstimator(endpoint, "raw", timeout_ms=2000.0); car.reset()
        th = threading.Thread(target=cycle, daemon=True); th.start()
        fell = 0
        for k in range(300):
            car.estimate(PerceptionSample(None, 2.0, 0.9, 2.0, 0.0), 1.0, 0.02)
            fell += car.diagnostics()["service_fallback"] == 1.0
            time.sleep(0.005)
        stop.set(); th.join(10)
        print(f"a car driving 300 steps beside {cycled[0]} hellos cycled from its address: {fell} answers lost, "
              f"{car.new_sessions} new sessions")
        car.close()
    finally:
        proc.terminate(); proc.wait(10)


if __name__ == "__main__":
    main()
