#!/usr/bin/env python3
"""touch_wall.py: the Python twin of examples/touch_wall. It registers a wall (the half-space
z < 0) and a weak spring field, has the server's simulated hand press the tool into the wall, and
prints time, hand target, tool height and force at about 20 Hz; --plot draws them.

Usage: touch_wall.py [host:port] [--lockstep] [--plot FILE.png] [--token T | --token-file F]
                     [--ca CA.pem [--cert C.pem --key K.pem] [--server-name NAME]]
  --lockstep  the server runs in LOCKSTEP time (hapticd --lockstep): this program advances it,
              and the output is the same on every run.
  --plot      also save a chart of height and force against time (needs matplotlib).
  --token, --token-file, --ca, --cert, --key, --server-name: a secured server (TLS, mutual TLS,
              tokens), as touch_wall and hapticctl take them (docs/deployment.md).

The hapticd package is found on PYTHONPATH (<build>/python after a build), installed
(python3-hapticd, cmake --install), or in the build tree beside this file. It is a compiled module
for the interpreter that built it (Debian's /usr/bin/python3): run the example with that one.
"""

import argparse
import pathlib
import sys
import sysconfig
import time

try:
    import hapticd
except ImportError:
    # Not on PYTHONPATH: the build tree beside this file, if one is there.
    build_package = pathlib.Path(__file__).resolve().parents[2] / "build" / "python"
    sys.path.insert(0, str(build_package))
    try:
        import hapticd
    except ImportError as missing:
        built = sorted(p.name for p in (build_package / "hapticd").glob("_native*.so"))
        sys.exit(f"touch_wall.py: cannot import hapticd ({missing}) with {sys.executable} "
                 f"(Python {sys.version.split()[0]}, module suffix "
                 f"{sysconfig.get_config_var('EXT_SUFFIX')}); "
                 + (f"the build tree holds {', '.join(built)}: run this with the interpreter "
                    "that built it (/usr/bin/python3 on Debian)" if built else
                    "build the project first (./scripts/run or cmake --build build), or install "
                    "python3-hapticd"))

import numpy as np  # after hapticd, whose absence is the likelier and better explained one

START_Z = 0.02        # hand target at the start, m
END_Z = -0.01         # 10 mm below the wall's surface, m
DESCENT_S = 2.0
HOLD_S = 1.0
HAND_STIFFNESS = 200.0  # N/m
HAND_DAMPING = 2.0      # N·s/m


def target_at(t):
    """The hand's target height at time t (s): down over DESCENT_S, then held."""
    return START_Z + min(t / DESCENT_S, 1.0) * (END_Z - START_Z)


def hand(t):
    return hapticd.OperatorInput.follow((0.0, 0.0, target_at(t)), HAND_STIFFNESS, HAND_DAMPING)


def run_lockstep(client, rate, rows):
    """Steps the server 10 ms at a time, moving the target between steps; a row every 50 ms."""
    ticks_per_step = max(1, int(rate / 100))
    t = 0.0
    step_index = 0
    while t < DESCENT_S + HOLD_S:
        target = target_at(t)  # what the hand pulls towards during this step
        client.set_operator(hand(t))
        tick = client.step(ticks_per_step)
        t = (step_index + 1) * ticks_per_step / rate
        if step_index % 5 == 0:
            rows.append((t, target, client.wait_for_tick(tick)))
        step_index += 1


def run_real_time(client, rows):
    """Moves the target every 10 ms of wall-clock time and prints what has arrived."""
    start = time.monotonic()
    first = last_server_time = last_row_time = None
    while (t := time.monotonic() - start) < DESCENT_S + HOLD_S:
        client.set_operator(hand(t))
        state = client.poll_state(timeout=0.0)
        if state is not None:
            if first is None:
                first = state.server_time
            elif state.server_time < last_server_time:
                # A restarted server counts from 0 again: carry on from the last row's time.
                first = state.server_time - last_row_time
            last_server_time, last_row_time = state.server_time, state.server_time - first
            rows.append((last_row_time, target_at(t), state))
        time.sleep(0.01)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("address", nargs="?", default="127.0.0.1:50051")
    parser.add_argument("--lockstep", action="store_true")
    parser.add_argument("--plot", metavar="FILE.png")
    parser.add_argument("--token", default="", help="bearer token (its role must allow it)")
    parser.add_argument("--token-file", metavar="F", help="read the token from F (first line)")
    parser.add_argument("--ca", metavar="CA.pem", help="speak TLS, trusting this CA")
    parser.add_argument("--cert", metavar="C.pem", help="with --ca: this client certificate (mTLS)")
    parser.add_argument("--key", metavar="K.pem", help="with --cert: its private key")
    parser.add_argument("--server-name", metavar="NAME", help="with --ca: the name to check")
    args = parser.parse_args()
    if args.token_file:
        try:
            with open(args.token_file, encoding="utf-8") as file:
                args.token = file.readline().rstrip("\n")
        except OSError as error:
            parser.error(f"--token-file: cannot read '{args.token_file}': {error.strerror}")
    tls = None
    if args.ca:
        tls = hapticd.TlsOptions(ca_file=args.ca, cert_file=args.cert or "", key_file=args.key or "",
                                 server_name=args.server_name or "")
    elif args.cert or args.key or args.server_name:
        parser.error("--cert, --key and --server-name need --ca (TLS)")

    try:
        with hapticd.Client(server_address=args.address, client_name="touch_wall.py", tls=tls,
                            token=args.token) as client:
            rate = client.device_info.loop_rate_hz
            client.subscribe(max(1, int(rate / 20)))
            wall = client.add_wall(hapticd.WallSpec(
                normal=(0, 0, 1), impedance=hapticd.Impedance(stiffness=1000.0, damping=1.0)))
            spring = client.add_spring_field(hapticd.SpringFieldSpec(
                anchor=(0, 0, START_Z), stiffness=20.0, max_force=2.0))
            print(f"touch_wall.py: {client.device_info.name} at {rate:.0f} Hz, "
                  f"{'lockstep' if args.lockstep else 'real'} time; wall z < 0 with K = 1000 N/m, "
                  f"B = 1 N*s/m")
            print(f"{'time_s':>7}  {'target_mm':>10}  {'z_mm':>8}  {'force_N':>9}  contact")
            rows = []
            if args.lockstep:
                run_lockstep(client, rate, rows)
            else:
                run_real_time(client, rows)
            for t, target, state in rows:
                print(f"{t:7.3f}  {target * 1e3:10.2f}  {state.position[2] * 1e3:8.3f}  "
                      f"{state.force[2]:9.3f}  {'yes' if state.contact_count else 'no'}")
            client.set_operator(hapticd.OperatorInput.release())
            print(f"touch_wall.py: done; {client.receive_counters().accepted} datagrams received")
            del wall, spring  # both leave the server here
    except hapticd.ConnectionError as error:
        # Starting a server is the fix only when nothing listens; a TLS or token mismatch says its own.
        start = ". Start one with ./scripts/run" if "nothing listens" in str(error) else ""
        sys.exit(f"touch_wall.py: {error}{start}")
    except hapticd.InvalidArgumentError as error:  # the options given (a token in clear, ...)
        print(f"touch_wall.py: {error}", file=sys.stderr)
        sys.exit(2)
    except hapticd.Error as error:
        sys.exit(f"touch_wall.py: {error}")

    if args.plot:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        t = np.array([row[0] for row in rows])
        z = np.array([row[2].position[2] for row in rows]) * 1e3
        force = np.array([row[2].force[2] for row in rows])
        figure, (top, bottom) = plt.subplots(2, 1, sharex=True, figsize=(6, 4.5))
        top.plot(t, [target_at(x) * 1e3 for x in t], "--", label="hand target")
        top.plot(t, z, label="tool")
        top.axhline(0.0, color="grey", linewidth=0.8)
        top.set_ylabel("height (mm)")
        top.legend()
        bottom.plot(t, force)
        bottom.set_ylabel("wall force z (N)")
        bottom.set_xlabel("time (s)")
        figure.tight_layout()
        figure.savefig(args.plot, dpi=110)
        print(f"touch_wall.py: chart in {args.plot}")


if __name__ == "__main__":
    main()
