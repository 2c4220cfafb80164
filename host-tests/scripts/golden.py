#!/usr/bin/env python3
"""Writes host-tests/golden.md: IK of hand-picked poses for the default geometry, in f64.

Independent of both kinematics-core and the Rust reference: the geometry is built from the
documented PairedLayout definition (pair k centred at 120k degrees, servos at 120k -+ 20,
platform joints at 120k -+ (60 - 20), arms tangential pointing away from the pair centre,
base radius 75 mm, platform radius 60 mm, arm 20 mm, rod 120 mm) in exact degrees; the
rotation is Rz Ry Rx multiplied out numerically; arm angles come from eq. 9 of "The
Mathematics of the Stewart Platform" and are then checked against a brute-force scan of the
rod-closure function; h0 from eq. 10; pulses from eq. 13/14 with W0 = 1500 us and
r = 1600/pi us/rad.

Run once from the repository root:  python3 host-tests/scripts/golden.py
"""
import math
import os

BASE_R, BASE_HALF = 75.0, 20.0
PLAT_R, PLAT_HALF = 60.0, 20.0
ARM, ROD = 20.0, 120.0
W0, RATE = 1500.0, 1600.0 / math.pi

POSES = [
    # name, x, y, z (mm), roll, pitch, yaw (degrees)
    ("home", 0, 0, 0, 0, 0, 0),
    ("heave up", 0, 0, 10, 0, 0, 0),
    ("heave down", 0, 0, -10, 0, 0, 0),
    ("surge", 10, 0, 0, 0, 0, 0),
    ("sway", 0, 10, 0, 0, 0, 0),
    ("roll", 0, 0, 0, 8, 0, 0),
    ("pitch", 0, 0, 0, 0, 8, 0),
    ("yaw", 0, 0, 0, 0, 0, 12),
    ("combined A", 4, -6, 5, 3, -4, 6),
    ("combined B", -5, 3, -4, -5, 2, -8),
]


def legs():
    out = []
    for k in range(3):
        c = 120.0 * k
        # servo 2k+1 (odd), then servo 2k+2 (even, its mirror image)
        for sense in (-1.0, 1.0):
            b_ang = math.radians(c + sense * BASE_HALF)
            p_ang = math.radians(c + sense * (60.0 - PLAT_HALF))
            beta = math.radians(c + sense * (BASE_HALF + 90.0))
            b = (BASE_R * math.cos(b_ang), BASE_R * math.sin(b_ang), 0.0)
            p = (PLAT_R * math.cos(p_ang), PLAT_R * math.sin(p_ang), 0.0)
            out.append((b, p, beta))
    return out


def matmul(a, b):
    return [[sum(a[r][k] * b[k][c] for k in range(3)) for c in range(3)] for r in range(3)]


def rotation(roll, pitch, yaw):
    cr, sr = math.cos(roll), math.sin(roll)
    cp, sp = math.cos(pitch), math.sin(pitch)
    cy, sy = math.cos(yaw), math.sin(yaw)
    rx = [[1, 0, 0], [0, cr, -sr], [0, sr, cr]]
    ry = [[cp, 0, sp], [0, 1, 0], [-sp, 0, cp]]
    rz = [[cy, -sy, 0], [sy, cy, 0], [0, 0, 1]]
    return matmul(matmul(rz, ry), rx)


def eq9(b, beta, q):
    l = [q[i] - b[i] for i in range(3)]
    big_l = sum(v * v for v in l) - (ROD * ROD - ARM * ARM)
    big_m = 2 * ARM * l[2]
    big_n = 2 * ARM * (math.cos(beta) * l[0] + math.sin(beta) * l[1])
    return math.asin(big_l / math.hypot(big_m, big_n)) - math.atan2(big_n, big_m)


def closure(b, beta, q, alpha):
    tip = (b[0] + ARM * math.cos(alpha) * math.cos(beta),
           b[1] + ARM * math.cos(alpha) * math.sin(beta),
           b[2] + ARM * math.sin(alpha))
    return math.dist(q, tip) - ROD


def check_root(b, beta, q, alpha):
    """The eq. 9 root closes the rod, and a fine scan finds no other closing angle within
    +-60 degrees of it (so it is the only candidate in the servo travel)."""
    assert abs(closure(b, beta, q, alpha)) < 1e-9
    steps = 2400
    for i in range(steps):
        a0 = alpha - math.radians(60) + math.radians(120) * i / steps
        a1 = alpha - math.radians(60) + math.radians(120) * (i + 1) / steps
        if closure(b, beta, q, a0) * closure(b, beta, q, a1) <= 0:
            assert a0 - 1e-9 <= alpha <= a1 + 1e-9, (alpha, a0, a1)
    # raising the arm brings the tip closer to the joint (the physical branch)
    assert closure(b, beta, q, alpha + 1e-6) < closure(b, beta, q, alpha - 1e-6)


def main():
    lg = legs()
    heights = []
    for b, p, _ in lg:
        dx, dy = p[0] - b[0], p[1] - b[1]
        heights.append(math.sqrt(ROD * ROD + ARM * ARM - dx * dx - dy * dy) - (p[2] - b[2]))
    h0 = sum(heights) / len(heights)
    assert max(heights) - min(heights) < 1e-9
    alpha0 = [eq9(b, beta, (p[0], p[1], p[2] + h0)) for b, p, beta in lg]
    rows = []
    for name, x, y, z, roll, pitch, yaw in POSES:
        r = rotation(math.radians(roll), math.radians(pitch), math.radians(yaw))
        alphas, pulses = [], []
        for i, (b, p, beta) in enumerate(lg):
            q = [x + sum(r[0][k] * p[k] for k in range(3)),
                 y + sum(r[1][k] * p[k] for k in range(3)),
                 h0 + z + sum(r[2][k] * p[k] for k in range(3))]
            a = eq9(b, beta, q)
            check_root(b, beta, q, a)
            servo = i + 1
            sign = 1.0 if servo % 2 == 0 else -1.0  # eq. 13 (even) / eq. 14 (odd)
            w = W0 + sign * (a - alpha0[i]) * RATE
            assert 1100.0 < w < 1900.0, (name, servo, w)
            alphas.append(math.degrees(a))
            pulses.append(w)
        rows.append((name, (x, y, z, roll, pitch, yaw), alphas, pulses))

    def num(v, places):
        s = f"{v:.{places}f}"
        return "0." + "0" * places if s == "-0." + "0" * places else s

    out = []
    out.append("# Golden poses for the default geometry\n")
    out.append("Default `PairedLayout`: base radius 75 mm, servo pairs 2 x 20 degrees apart, "
               "platform radius 60 mm, joint pairs 2 x 20 degrees apart, arm a = 20 mm, rod s = 120 mm; "
               "default servos (W0 = 1500 us, r = 1600/pi us/rad, even servos add, odd subtract). "
               "Computed in f64 by `host-tests/scripts/golden.py` ('The Mathematics of the Stewart "
               "Platform', eq. 9, 10, 13, 14, each "
               "root checked by a scan of the rod-closure function), not by the firmware. "
               "`host-tests/tests/golden.rs` parses this file and checks the core against it.\n")
    out.append("## Derived constants\n")
    out.append("| quantity | value |")
    out.append("| --- | ---: |")
    out.append(f"| h0 (mm) | {num(h0, 3)} |")
    out.append(f"| alpha0 (deg) | {num(math.degrees(alpha0[0]), 3)} |")
    out.append("")
    out.append("## Poses\n")
    out.append("| pose | x (mm) | y (mm) | z (mm) | roll (deg) | pitch (deg) | yaw (deg) |")
    out.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, v, _, _ in rows:
        out.append(f"| {name} | " + " | ".join(str(c) for c in v) + " |")
    out.append("")
    out.append("## Arm angles alpha_i (degrees above horizontal)\n")
    out.append("| pose | servo 1 | servo 2 | servo 3 | servo 4 | servo 5 | servo 6 |")
    out.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, _, alphas, _ in rows:
        out.append(f"| {name} | " + " | ".join(num(a, 3) for a in alphas) + " |")
    out.append("")
    out.append("## Pulse widths W_i (us)\n")
    out.append("| pose | servo 1 | servo 2 | servo 3 | servo 4 | servo 5 | servo 6 |")
    out.append("| --- | ---: | ---: | ---: | ---: | ---: | ---: |")
    for name, _, _, pulses in rows:
        out.append(f"| {name} | " + " | ".join(num(w, 2) for w in pulses) + " |")
    path = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "golden.md")
    with open(path, "w", encoding="utf-8") as f:
        f.write("\n".join(out) + "\n")


if __name__ == "__main__":
    main()
