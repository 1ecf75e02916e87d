#!/usr/bin/env python3
"""How a Python on_state callback keeps up with a real-time server: for `--seconds`, a callback
that copies each State's position and force into NumPy arrays; prints the samples it saw per
second, what the SDK skipped or lost, and this process's CPU time per sample (all threads: the
SDK's receive thread and the callback under the GIL).

Usage: PYTHONPATH=build/python python3 python/bench/callback_rate.py [--server host:port]
       [--seconds 10]   (without --server it starts build/server/app/hapticd, real time)
"""

import argparse
import json
import os
import pathlib
import signal
import subprocess
import tempfile
import threading
import time

import numpy as np

import hapticd


def start_server(binary):
    folder = pathlib.Path(tempfile.mkdtemp(prefix="hapticd-bench-"))
    ready = folder / "ready.json"
    process = subprocess.Popen([binary, "--grpc-address", "127.0.0.1:0", "--udp-port", "0",
                                "--ready-file", str(ready)], stdout=subprocess.DEVNULL,
                               stderr=subprocess.DEVNULL)
    give_up = time.monotonic() + 20
    while not ready.exists():
        if process.poll() is not None or time.monotonic() > give_up:
            raise SystemExit("callback_rate: hapticd did not start")
        time.sleep(0.01)
    return process, f"127.0.0.1:{json.loads(ready.read_text())['grpc_port']}"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--server")
    parser.add_argument("--seconds", type=float, default=10.0)
    args = parser.parse_args()
    process = None
    address = args.server
    if address is None:
        binary = os.environ.get("HAPTICD_BINARY", "build/server/app/hapticd")
        process, address = start_server(binary)
    try:
        capacity = int(args.seconds * 20_000) + 1000
        positions = np.empty((capacity, 3))
        forces = np.empty((capacity, 3))
        ticks = np.empty(capacity, dtype=np.uint64)
        count = 0
        lock = threading.Lock()

        def on_state(state):
            nonlocal count
            with lock:
                if count < capacity:
                    positions[count] = state.position
                    forces[count] = state.force
                    ticks[count] = state.tick
                    count += 1

        with hapticd.Client(server_address=address, client_name="callback_rate") as client:
            rate = client.device_info.loop_rate_hz
            client.on_state(on_state)
            time.sleep(0.5)  # past the first samples' path challenge
            with lock:
                count = 0
            cpu_before = time.process_time()
            started = time.monotonic()
            counters_before = client.receive_counters()
            time.sleep(args.seconds)
            with lock:
                seen = count
            elapsed = time.monotonic() - started
            cpu = time.process_time() - cpu_before
            counters = client.receive_counters()
            client.on_state(None)
        gaps = np.diff(ticks[:seen].astype(np.int64))
        print(f"callback_rate: server at {rate:.0f} Hz, {elapsed:.1f} s")
        print(f"  samples seen by the callback  {seen / elapsed:9.1f} /s  "
              f"({100.0 * seen / (elapsed * rate):.2f} % of ticks)")
        print(f"  largest tick gap              {int(gaps.max()) if len(gaps) else 0:9d}")
        print(f"  callback_skipped              {counters.callback_skipped - counters_before.callback_skipped:9d}")
        print(f"  skipped (queued, not newest)  {counters.skipped - counters_before.skipped:9d}")
        print(f"  lost on the way               {counters.lost - counters_before.lost:9d}")
        print(f"  process CPU per sample        {1e6 * cpu / max(seen, 1):9.1f} µs "
              f"({100.0 * cpu / elapsed:.1f} % of a core)")
    finally:
        if process is not None:
            process.send_signal(signal.SIGTERM)
            process.wait(timeout=20)


if __name__ == "__main__":
    main()
