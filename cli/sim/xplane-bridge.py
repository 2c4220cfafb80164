#!/usr/bin/env python3
"""An example bridge: X-Plane's UDP data output to the telemetry line `hexapod cue` reads
(docs/cueing.md): `time_s, ax, ay, az, p, q, r, phi, theta, psi` (s; ft/s^2 in body axes,
x forward, y right, z down; rad/s; rad).

In X-Plane (Settings, Data Output): send to this machine's IP on port 49005 ("Network via
UDP"), rows 1 (times), 4 (Mach, VVI, g-load), 16 (angular velocities) and 17 (pitch, roll,
headings), at 60 per second. Then:

    python3 cli/sim/xplane-bridge.py --listen 0.0.0.0:49005 --to 127.0.0.1:5139
    hexapod cue --port /dev/ttyACM0

X-Plane sends "DATA", one byte, then 36-byte rows: a 32-bit row index and eight 32-bit
floats, little-endian. Not tested against X-Plane here: check the signs on your version by
accelerating down the runway (the platform must tilt nose up, negative pitch) and flip the
SIGNS below if an axis goes the wrong way.
"""

import argparse
import math
import socket
import struct

G_FT_S2 = 32.174
# g-loads -> specific force in body axes: axial (forward), side (right), normal (up, so -z).
SIGNS = {"axial": 1.0, "side": 1.0, "normal": -1.0}


def rows(packet):
    """The rows of a DATA packet: {index: eight floats}."""
    if not packet.startswith(b"DATA") or (len(packet) - 5) % 36:
        return {}
    out = {}
    for at in range(5, len(packet), 36):
        index, *values = struct.unpack_from("<i8f", packet, at)
        out[index] = values
    return out


def line(r):
    """The telemetry line, or None until every row has come."""
    if not all(k in r for k in (1, 4, 16, 17)):
        return None
    time_s = r[1][1]  # "totl": total time, s
    g_normal, g_axial, g_side = r[4][4], r[4][5], r[4][6]
    q, p, rr = r[16][0], r[16][1], r[16][2]  # rad/s
    pitch, roll, heading = (math.radians(v) for v in r[17][:3])
    ax = SIGNS["axial"] * g_axial * G_FT_S2
    ay = SIGNS["side"] * g_side * G_FT_S2
    az = SIGNS["normal"] * g_normal * G_FT_S2
    return f"{time_s:.4f},{ax:.5f},{ay:.5f},{az:.5f},{p:.6f},{q:.6f},{rr:.6f},{roll:.6f},{pitch:.6f},{heading:.6f}\n"


def address(text):
    host, port = text.rsplit(":", 1)
    return host, int(port)


def main():
    parser = argparse.ArgumentParser(description="X-Plane UDP data output to hexapod cue")
    parser.add_argument("--listen", type=address, default=("0.0.0.0", 49005))
    parser.add_argument("--to", type=address, default=("127.0.0.1", 5139))
    args = parser.parse_args()
    inbound = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    inbound.bind(args.listen)
    outbound = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    latest = {}
    while True:
        packet, _ = inbound.recvfrom(65536)
        latest.update(rows(packet))
        text = line(latest)
        if text:
            outbound.sendto(text.encode(), args.to)


if __name__ == "__main__":
    main()
