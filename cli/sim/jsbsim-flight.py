#!/usr/bin/env python3
"""A short scripted flight in JSBSim (the `jsbsim` package from PyPI), its telemetry sent over
UDP by JSBSim itself with the output directive cli/sim/jsbsim-output.xml: what `hexapod cue`
reads (docs/cueing.md). No FlightGear, no display: a way to see a platform fly, and the
end-to-end test's flight (emulator/test/cue.test.js).

The flight: a Cessna 172 (c172x) on the runway, engine run up with the brakes on, brakes off
(the take-off run: a forward acceleration), rotation at 51 kt with the autopilot holding a
climb, then at 100 ft a turn of 150 degrees by its roll autopilot (a sustained turn), then the
telemetry ends. It runs at `--speed` times real time (1: real time), and prints each phase
as it begins (`phase NAME SIM_TIME_S`) on standard output.

    python3 cli/sim/jsbsim-flight.py --port 5139 [--speed 1] [--end-s 60]
"""

import argparse
import math
import os
import sys
import tempfile
import time

import jsbsim

TURN_DEG = 150.0
HERE = os.path.dirname(os.path.abspath(__file__))


def directive(port, rate_hz):
    """The shipped output directive, with its port and rate set (a temporary copy)."""
    with open(os.path.join(HERE, "jsbsim-output.xml"), encoding="utf-8") as f:
        text = f.read()
    text = text.replace('port="5139"', f'port="{port}"').replace('rate="60"', f'rate="{rate_hz}"')
    handle, path = tempfile.mkstemp(suffix=".xml")
    with os.fdopen(handle, "w", encoding="utf-8") as f:
        f.write(text)
    return path


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--port", type=int, default=5139, help="UDP port on 127.0.0.1")
    parser.add_argument("--rate", type=int, default=60, help="telemetry lines per simulated second")
    parser.add_argument("--speed", type=float, default=1.0, help="times real time")
    parser.add_argument("--end-s", type=float, default=60.0, help="simulated seconds to fly")
    args = parser.parse_args()

    fdm = jsbsim.FGFDMExec(None)
    fdm.set_debug_level(0)
    path = directive(args.port, args.rate)
    try:
        fdm.set_output_directive(path)
        fdm.load_model("c172x")
        fdm.load_ic("reset00", True)
        fdm.set_dt(1.0 / 120.0)
        fdm.run_ic()
    finally:
        os.unlink(path)
    for name in ["fcs/left-brake-cmd-norm", "fcs/right-brake-cmd-norm", "fcs/center-brake-cmd-norm"]:
        fdm[name] = 1.0
    fdm["fcs/mixture-cmd-norm"] = 1.0
    fdm["propulsion/magneto_cmd"] = 3
    fdm["propulsion/starter_cmd"] = 1
    fdm["fcs/throttle-cmd-norm"] = 1.0
    # The roll autopilot holds the wings level, then the heading asked for (JSBSim's generic
    # Autopilot system, as its c1723.xml script uses it).
    fdm["guidance/heading-selector-switch"] = 1
    fdm["guidance/specified-heading-rad"] = fdm["attitude/psi-rad"]
    fdm["ap/roll-attitude-mode"] = 1
    fdm["ap/autopilot-roll-on"] = 1
    fdm["ap/altitude_hold"] = 0
    phase = None

    def enter(name):
        nonlocal phase
        phase = name
        print(f"phase {name} {fdm.get_sim_time():.3f}", flush=True)

    enter("run-up")
    start = time.monotonic()
    heading = None
    while fdm.get_sim_time() < args.end_s:
        t = fdm.get_sim_time()
        if phase == "run-up" and t >= 3.0:
            for name in ["fcs/left-brake-cmd-norm", "fcs/right-brake-cmd-norm",
                         "fcs/center-brake-cmd-norm"]:
                fdm[name] = 0.0
            fdm["fcs/flap-cmd-norm"] = 0.33
            enter("take-off-run")
        elif phase == "take-off-run" and fdm["velocities/vc-kts"] >= 51.0:
            fdm["ap/altitude_setpoint"] = 1000.0
            fdm["ap/altitude_hold"] = 1
            enter("rotate")
        elif phase == "rotate" and fdm["position/h-agl-ft"] >= 100.0:
            heading = (fdm["attitude/psi-rad"] + math.radians(TURN_DEG)) % (2 * math.pi)
            fdm["guidance/specified-heading-rad"] = heading
            enter("turn")
        fdm.run()
        # Real time (times --speed): wait for the wall clock to catch up.
        ahead = fdm.get_sim_time() / args.speed - (time.monotonic() - start)
        if ahead > 0:
            time.sleep(ahead)
    enter("end")
    print(f"heading {fdm['attitude/psi-deg']:.1f} altitude {fdm['position/h-agl-ft']:.0f} ft", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
