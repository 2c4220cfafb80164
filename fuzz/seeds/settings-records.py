#!/usr/bin/env python3
"""Writes the stored-settings seeds of the `settings` fuzz target (seeds/settings/record-*).

An encoder independent of the firmware's (`control/src/record.rs`), written from the format
table in that file's documentation: Python `struct` and `zlib.crc32`. The seeds must decode
(robustness/tests/seeds.rs checks that), so the fuzzer starts from records that get past the
checksum. Run it again whenever the record format changes:

    python3 fuzz/seeds/settings-records.py
"""
import math
import os
import struct
import zlib

FORMAT_VERSION = 5
PAYLOAD_LEN = 236
# Format 4: no pivot, 12 bytes shorter, and no servo speed ratings (their byte reserved, 0).
FORMAT_VERSION_NO_PIVOT = 4
# Format 3 (boards in the field hold it): no baud rate and no pivot, 16 bytes shorter.
FORMAT_VERSION_NO_BAUD = 3
PIN_OFF = 0xFF
AXES = ['x', 'y', 'z', 'roll', 'pitch', 'yaw']
RATE = 1600 / math.pi  # the default servo rate, us/rad


def record(sequence, frame_hz, speeds, layout, servos, accels=(0.0, 0.0),
           stream_scale=(25.0, 25.0, 15.0, 15.0, 15.0, 20.0), stream_bits=8,
           stream_order=('x', 'y', 'z', 'roll', 'pitch', 'yaw'), estop_pin=None,
           estop_home=False, power_pin=None, payload_g=0.0, com_mm=(0.0, 0.0, 0.0),
           ratings_kgcm=(0.0,) * 6, speeds_s_60deg=(0.0,) * 6, baud=115200,
           pivot_mm=(0.0, 0.0, 0.0),
           version=FORMAT_VERSION):
    """sequence: the save's number; speeds: (mm/s, deg/s, link timeout s); layout: base radius,
    base half angle, platform radius, platform half angle, arm, rod; servos: six (trim, rate,
    min, max, reversed); accels: (mm/s^2, deg/s^2); stream_order: six axis names or None;
    pins: GPIO or None; payload_g, com_mm: the payload; ratings_kgcm: six torque ratings
    (kgf cm, kept in hundredths; 0 not rated); speeds_s_60deg: six speed ratings (s per 60
    degrees, kept in hundredths; 0 not rated); baud: UART0's rate; pivot_mm: the rotation
    centre (platform frame, mm); version: 5, or 4 for the older format without the pivot and
    the speed ratings, or 3 for the oldest, without the baud rate either."""
    if version != FORMAT_VERSION:
        assert all(v == 0.0 for v in speeds_s_60deg)
    payload = struct.pack('<HH', frame_hz, 0) + struct.pack('<3f', *speeds)
    payload += struct.pack('<6f', *layout)
    for (trim, rate, lo, hi, reversed_), rating, speed in zip(servos, ratings_kgcm,
                                                              speeds_s_60deg):
        payload += struct.pack('<4fBBH', trim, rate, lo, hi, 1 if reversed_ else 0,
                               round(speed * 100), round(rating * 100))
    payload += struct.pack('<2f', *accels) + struct.pack('<6f', *stream_scale)
    payload += bytes([stream_bits] + [6 if a is None else AXES.index(a) for a in stream_order])
    pin = lambda p: PIN_OFF if p is None else p
    payload += bytes([pin(estop_pin), 1 if estop_home else 0, pin(power_pin), 0, 0])
    payload += struct.pack('<f3f', payload_g, *com_mm)
    if version in (FORMAT_VERSION, FORMAT_VERSION_NO_PIVOT):
        payload += struct.pack('<I', baud)
    else:
        assert version == FORMAT_VERSION_NO_BAUD
    if version == FORMAT_VERSION:
        payload += struct.pack('<3f', *pivot_mm)
    lengths = {FORMAT_VERSION: PAYLOAD_LEN, FORMAT_VERSION_NO_PIVOT: PAYLOAD_LEN - 12,
               FORMAT_VERSION_NO_BAUD: PAYLOAD_LEN - 16}
    assert len(payload) == lengths[version]
    body = b'HXPS' + struct.pack('<HH', version, len(payload)) + payload
    body += struct.pack('<I', sequence)
    return body + struct.pack('<I', zlib.crc32(body))


def default_servos():
    travel = math.pi / 4 * RATE
    return [(1500.0, RATE, 1500.0 - travel, 1500.0 + travel, n % 2 == 1) for n in range(1, 7)]


# The same custom settings in every format.
CUSTOM = dict(
    sequence=0xFFFFFFFF, frame_hz=100, speeds=(20.0, 0.0, 2.5),
    layout=(90.0, 15.0, 50.0, 25.0, 25.0, 110.0),
    servos=[(trim, RATE, 1000.0, 2000.0, n % 2 == 1)
            for n, trim in zip(range(1, 7), (1450.0, 1500.0, 1520.0, 1490.0, 1510.0, 1500.0))],
    accels=(400.0, 0.0), stream_scale=(30.0, -30.0, 10.0, 0.0, 12.5, 45.0), stream_bits=12,
    stream_order=('roll', None, 'z', 'x', 'yaw', 'pitch'), estop_pin=15, estop_home=True,
    power_pin=22, payload_g=1500.0, com_mm=(5.0, -2.5, 40.0),
    ratings_kgcm=(10.0, 10.0, 12.5, 0.0, 9.99, 600.0))

SEEDS = {
    'record-default': record(1, 50, (50.0, 60.0, 0.0), (75.0, 20.0, 60.0, 20.0, 20.0, 120.0),
                             default_servos()),
    'record-custom': record(**CUSTOM, baud=921600, pivot_mm=(10.0, -5.0, 300.0),
                            speeds_s_60deg=(0.1, 0.1, 0.12, 0.0, 2.55, 0.01)),
    'record-v4-custom': record(**CUSTOM, baud=921600, version=FORMAT_VERSION_NO_PIVOT),
    'record-v3-custom': record(**CUSTOM, version=FORMAT_VERSION_NO_BAUD),
}

if __name__ == '__main__':
    folder = os.path.join(os.path.dirname(os.path.abspath(__file__)), 'settings')
    for name, data in SEEDS.items():
        with open(os.path.join(folder, name), 'wb') as f:
            f.write(data)
        print(f'{name}: {len(data)} bytes')
