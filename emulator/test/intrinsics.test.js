// The firmware's own float and division routines (firmware/src/intrinsics.rs: the `__aeabi_*`
// functions the compiler calls for `f32` arithmetic, comparisons, conversions and integer
// division) against the host's IEEE 754 arithmetic, on the emulated chip with the real boot
// ROM: each routine of the firmware ELF is called in place (src/chip/call.js) over a grid of
// operands (zeros of both signs, denormals, the ends of the normal range, infinities, NaNs,
// the exponents where the routines choose between the ROM and the exact fallback, rounding
// ties) and random ones. Bit for bit, but for NaN, where any NaN will do.
//
// JavaScript computes in f64; rounding an f64 sum, difference, product or quotient of two f32
// values to f32 (Math.fround) gives the correctly rounded f32 result: 53 >= 2 * 24 + 2 bits
// (the double rounding is innocuous).
//
// The ROM's own routines, called directly, are characterised too: where they differ from IEEE
// (the test prints it) must lie outside the operands for which the firmware's routines call
// them.

import assert from 'node:assert/strict';
import { before, test } from 'node:test';

import { DEFAULT_ELF, EmulatedBoard } from '../src/chip/board.js';
import { callFunction } from '../src/chip/call.js';
import { sizedSymbols, symbolValues } from '../src/chip/elf.js';

const ROUTINES = [
  '__aeabi_fadd',
  '__aeabi_fsub',
  '__aeabi_fmul',
  '__aeabi_fdiv',
  '__aeabi_fcmpeq',
  '__aeabi_fcmplt',
  '__aeabi_fcmple',
  '__aeabi_fcmpgt',
  '__aeabi_fcmpge',
  '__aeabi_fcmpun',
  '__aeabi_f2iz',
  '__aeabi_f2uiz',
  '__aeabi_i2f',
  '__aeabi_ui2f',
  '__aeabi_uidivmod',
  '__aeabi_idivmod',
  '__aeabi_uidiv',
  '__aeabi_idiv',
  '__aeabi_memcpy',
  '__aeabi_memcpy4',
  '__aeabi_memset',
  '__aeabi_memset4',
  '__aeabi_memclr',
  '__aeabi_memclr4',
  '__aeabi_lmul',
];

const f32 = new Float32Array(1);
const u32 = new Uint32Array(f32.buffer);
const toFloat = (bits) => {
  u32[0] = bits;
  return f32[0];
};
const toBits = (x) => {
  f32[0] = x;
  return u32[0];
};
const hex = (bits) => `0x${(bits >>> 0).toString(16).padStart(8, '0')}`;
const exponentField = (bits) => (bits >>> 23) & 0xff;

/** xorshift32: the same operands on every run. */
function random(seed) {
  let s = seed >>> 0 || 1;
  return () => {
    s ^= s << 13;
    s >>>= 0;
    s ^= s >>> 17;
    s ^= s << 5;
    s >>>= 0;
    return s;
  };
}

/** Operands: the edges of every class, both signs. */
function gridOperands() {
  const magnitudes = [
    0, // zero
    1, // smallest denormal
    0x00400000,
    0x007fffff, // largest denormal
    0x7f800000, // infinity
    0x7fc00000, // quiet NaN
    0x7f800001, // signalling NaN
    0x7fffffff,
  ];
  // Normal numbers at the exponents where the routines' choices change, and elsewhere.
  for (const e of [
    1, 2, 22, 23, 24, 25, 26, 60, 100, 125, 126, 127, 128, 129, 150, 200, 251, 252, 253, 254,
  ]) {
    for (const m of [0, 1, 0x400000, 0x7fffff, 0x2aaaab]) {
      magnitudes.push((e << 23) | m);
    }
  }
  const values = [];
  for (const m of magnitudes) {
    values.push(m, (m | 0x80000000) >>> 0);
  }
  return values;
}

/** Random operands: any bit pattern; moderate magnitudes; near-cancelling pairs; ties. */
function randomPairs(count, seed) {
  const next = random(seed);
  const pairs = [];
  const moderate = () => {
    const e = 127 - 30 + (next() % 61);
    return ((next() & 0x80000000) | (e << 23) | (next() & 0x7fffff)) >>> 0;
  };
  for (let i = 0; i < count; i++) {
    pairs.push([next(), next()]);
    const a = moderate();
    pairs.push([a, moderate()]);
    // b close to -a (or a): cancellation in a sum, a quotient near one.
    const near = (a + (next() % 7) - 3) >>> 0;
    pairs.push([a, (near ^ (next() & 0x80000000)) >>> 0]);
    // A sum exactly halfway between two floats: a plus an odd multiple of half its ulp.
    const e = exponentField(a);
    pairs.push([a, toBits(Math.fround((2 * (next() % 3) + 1) * 2 ** (e - 127 - 24)))]);
    // Products of 12-bit integers (many exactly halfway at 24 bits), scaled.
    const x = ((1 << 12) + (next() % (1 << 12))) * 2 ** ((next() % 41) - 20);
    const y = ((1 << 12) + (next() % (1 << 12))) * 2 ** ((next() % 41) - 20);
    pairs.push([toBits(x), toBits(y)]);
  }
  return pairs;
}

const ARITHMETIC = {
  add: (a, b) => a + b,
  sub: (a, b) => a - b,
  mul: (a, b) => a * b,
  div: (a, b) => a / b,
};
const COMPARISONS = {
  __aeabi_fcmpeq: (a, b) => a === b,
  __aeabi_fcmplt: (a, b) => a < b,
  __aeabi_fcmple: (a, b) => a <= b,
  __aeabi_fcmpgt: (a, b) => a > b,
  __aeabi_fcmpge: (a, b) => a >= b,
  __aeabi_fcmpun: (a, b) => Number.isNaN(a) || Number.isNaN(b),
};

/** The IEEE result's bits, or null for NaN (any NaN will do). */
function ieee(op, a, b) {
  const r = Math.fround(ARITHMETIC[op](toFloat(a), toFloat(b)));
  return Number.isNaN(r) ? null : toBits(r);
}

const sameResult = (expected, got) =>
  expected === null ? Number.isNaN(toFloat(got)) : expected === got >>> 0;

/** An operand's or result's class, its sign aside. */
function classOf(bits) {
  const e = exponentField(bits);
  const m = bits & 0x7fffff;
  if (e === 0) {
    return m === 0 ? '0' : 'denormal';
  }
  if (e === 255) {
    return m === 0 ? 'inf' : 'NaN';
  }
  return 'normal';
}

let board;
let address;
let rom;
let pairs;
before(() => {
  board = new EmulatedBoard({ elf: DEFAULT_ELF });
  board.boot();
  address = symbolValues(DEFAULT_ELF, ROUTINES);
  assert.deepEqual(
    Object.keys(address).sort(),
    [...ROUTINES].sort(),
    'every routine is in the ELF',
  );
  pairs = [];
  const grid = gridOperands();
  for (const a of grid) {
    for (const b of grid) {
      pairs.push([a, b]);
    }
  }
  pairs.push(...randomPairs(4000, 2024));
  // The ROM's routines, as the firmware's slots hold them after a first call.
  callFunction(board, address.__aeabi_fadd, [toBits(1), toBits(2)]);
  const slot = (name) => {
    const symbol = sizedSymbols(DEFAULT_ELF).find((s) =>
      s.name.includes(`10intrinsics${name.length}${name}`),
    );
    assert.ok(symbol, name);
    return board.mcu.readUint32(symbol.value);
  };
  rom = { add: slot('ROM_FADD'), mul: slot('ROM_FMUL'), div: slot('ROM_FDIV') };
  for (const [name, entry] of Object.entries(rom)) {
    assert.ok(entry < 0x4000 && entry & 1, `the ROM's ${name}: ${hex(entry)}`);
  }
});

for (const [op, name] of [
  ['add', '__aeabi_fadd'],
  ['sub', '__aeabi_fsub'],
  ['mul', '__aeabi_fmul'],
  ['div', '__aeabi_fdiv'],
]) {
  test(`${name} gives IEEE's result for every operand pair`, () => {
    const wrong = [];
    for (const [a, b] of pairs) {
      const expected = ieee(op, a, b);
      const got = callFunction(board, address[name], [a, b]).r0;
      if (!sameResult(expected, got)) {
        wrong.push(
          `${hex(a)} ${op} ${hex(b)}: ${hex(got)}, IEEE ${expected === null ? 'NaN' : hex(expected)}`,
        );
      }
    }
    assert.deepEqual(wrong.slice(0, 10), [], `${wrong.length} of ${pairs.length} differ`);
  });
}

/**
 * Whether the firmware's routine calls the ROM for these operands (firmware/src/intrinsics.rs):
 * by their exponent fields, and whether they are zeros.
 */
const normal = (e) => e >= 1 && e <= 254;
const FAST = {
  add: (ea, eb, za, zb) =>
    za
      ? zb || normal(eb)
      : (ea >= 24 && ea <= 253 && (zb || (eb >= 24 && eb <= 253))) ||
        (normal(ea) && ea <= 253 && normal(eb) && eb <= 253 && ea + eb >= 48),
  mul: (ea, eb, za, zb) =>
    za ? zb || normal(eb) : normal(ea) && (zb || (normal(eb) && ea + eb >= 128 && ea + eb <= 379)),
  div: (ea, eb, za, zb) =>
    za ? normal(eb) : normal(ea) && (zb || (normal(eb) && ea - eb >= -125 && ea - eb <= 126)),
};
const isZero = (bits) => (bits & 0x7fffffff) === 0;

for (const op of ['add', 'mul', 'div']) {
  test(`the ROM's f${op} is IEEE's wherever the firmware calls it (and where it is not)`, (t) => {
    let fast = 0;
    const wrongFast = [];
    const outside = new Map();
    for (const [a, b] of pairs) {
      const expected = ieee(op, a, b);
      const got = callFunction(board, rom[op], [a, b]).r0;
      const isFast = FAST[op](exponentField(a), exponentField(b), isZero(a), isZero(b));
      fast += isFast ? 1 : 0;
      if (sameResult(expected, got)) {
        continue;
      }
      if (isFast) {
        wrongFast.push(`${hex(a)} ${op} ${hex(b)}: ${hex(got)}, IEEE ${hex(expected ?? 0)}`);
      } else {
        const key = `${classOf(a)} ${op} ${classOf(b)}: IEEE ${expected === null ? 'NaN' : classOf(expected)}, ROM ${classOf(got)}`;
        outside.set(key, (outside.get(key) ?? 0) + 1);
      }
    }
    assert.deepEqual(wrongFast, [], `${wrongFast.length} of ${fast} differ`);
    assert.ok(fast > pairs.length / 3, `${fast} of ${pairs.length} operand pairs go to the ROM`);
    t.diagnostic(`the ROM's f${op}: ${fast} pairs it gets, all IEEE; where it differs elsewhere:`);
    for (const [key, count] of [...outside].sort()) {
      t.diagnostic(`  ${key} (${count})`);
    }
  });
}

test('the comparisons are IEEE: zeros equal, NaN unordered', () => {
  const wrong = [];
  for (const [a, b] of pairs) {
    for (const [name, relation] of Object.entries(COMPARISONS)) {
      const expected = relation(toFloat(a), toFloat(b)) ? 1 : 0;
      const got = callFunction(board, address[name], [a, b]).r0;
      if (got !== expected) {
        wrong.push(`${name}(${hex(a)}, ${hex(b)}) = ${got}`);
      }
    }
  }
  assert.deepEqual(wrong.slice(0, 10), [], `${wrong.length} differ`);
});

test("float to integer conversions truncate and saturate as Rust's `as` does", () => {
  const next = random(7);
  const operands = gridOperands();
  for (let i = 0; i < 20000; i++) {
    operands.push(next(), toBits(((next() | 0) / 2 ** (next() % 32)) * (next() & 1 ? 1 : 0.999)));
  }
  for (const x of [
    2 ** 31,
    2 ** 31 - 128,
    2 ** 32,
    2 ** 32 - 256,
    -(2 ** 31),
    -(2 ** 31) - 256,
    0.5,
    -0.5,
    1,
    -1,
    1.5,
    -1.5,
  ]) {
    operands.push(toBits(x));
  }
  const wrong = [];
  for (const bits of operands) {
    const x = toFloat(bits);
    const toInt = Number.isNaN(x) ? 0 : Math.min(2 ** 31 - 1, Math.max(-(2 ** 31), Math.trunc(x)));
    const toUint = Number.isNaN(x) ? 0 : Math.min(2 ** 32 - 1, Math.max(0, Math.trunc(x)));
    const i = callFunction(board, address.__aeabi_f2iz, [bits]).r0 | 0;
    const u = callFunction(board, address.__aeabi_f2uiz, [bits]).r0;
    if (i !== toInt || u !== toUint) {
      wrong.push(`${hex(bits)} (${x}): f2iz ${i} (${toInt}), f2uiz ${u} (${toUint})`);
    }
  }
  assert.deepEqual(wrong.slice(0, 10), [], `${wrong.length} of ${operands.length} differ`);
});

test('integer to float conversions round to nearest, ties to even', () => {
  const next = random(11);
  const operands = [
    0, 1, 2, 3, 0x7fffffff, 0x80000000, 0x80000001, 0xffffffff, 0xffffff80, 0xffffff7f,
  ];
  for (let shift = 0; shift < 8; shift++) {
    // 2^24 + k near a tie at every scale.
    for (let k = 0; k < 8; k++) {
      operands.push((((1 << 24) + k) << shift) >>> 0, ((((1 << 24) + k) << shift) | 1) >>> 0);
    }
  }
  for (let i = 0; i < 20000; i++) {
    operands.push(next(), next() >>> (next() % 32));
  }
  const wrong = [];
  for (const x of operands) {
    const unsigned = callFunction(board, address.__aeabi_ui2f, [x]).r0;
    const signed = callFunction(board, address.__aeabi_i2f, [x]).r0;
    if (unsigned !== toBits(Math.fround(x >>> 0)) || signed !== toBits(Math.fround(x | 0))) {
      wrong.push(`${hex(x)}: ui2f ${hex(unsigned)}, i2f ${hex(signed)}`);
    }
  }
  assert.deepEqual(wrong.slice(0, 10), [], `${wrong.length} of ${operands.length} differ`);
});

test('integer division: quotient and remainder, signed and unsigned', () => {
  const next = random(13);
  const wrong = [];
  for (let i = 0; i < 20000; i++) {
    const n = next();
    const d = i % 2 ? next() >>> (next() % 32) || 1 : (next() % 1000) + 1;
    const { r0: q, r1: r } = callFunction(board, address.__aeabi_uidivmod, [n, d]);
    const { r0: plain } = callFunction(board, address.__aeabi_uidiv, [n, d]);
    if (q !== Math.floor(n / d) || r !== n % d || plain !== q) {
      wrong.push(`${n} / ${d}: ${q} r ${r}`);
    }
    const sn = n | 0;
    const sd = (i % 3 ? d : -d) | 0;
    if (sn === -(2 ** 31) && sd === -1) {
      continue; // overflow: Rust checks for it before dividing
    }
    const { r0: sq, r1: sr } = callFunction(board, address.__aeabi_idivmod, [sn, sd]);
    const { r0: splain } = callFunction(board, address.__aeabi_idiv, [sn, sd]);
    if ((sq | 0) !== Math.trunc(sn / sd) || (sr | 0) !== sn % sd || splain !== sq) {
      wrong.push(`${sn} / ${sd}: ${sq | 0} r ${sr | 0}`);
    }
  }
  assert.deepEqual(wrong.slice(0, 10), [], `${wrong.length} differ`);
});

test('a division interrupted in the hardware divider finds its result there afterwards', () => {
  // As if an interrupt came between another division's operand writes and its result reads
  // (the divider is dirty): the routines that use the divider put its state back.
  const SIO = 0xd0000000;
  const read = (offset) => board.mcu.readUint32(SIO + offset);
  for (const { name, args, expected } of [
    { name: '__aeabi_uidivmod', args: [1000, 7], expected: [142, 6] },
    { name: '__aeabi_idivmod', args: [-1000, 7], expected: [-142 >>> 0, -6 >>> 0] },
    { name: '__aeabi_fdiv', args: [toBits(1), toBits(3)], expected: [toBits(Math.fround(1 / 3))] },
  ]) {
    board.mcu.writeUint32(SIO + 0x60, 1234567);
    board.mcu.writeUint32(SIO + 0x64, 89);
    assert.equal(read(0x78) & 2, 2, 'dirty');
    const { r0, r1 } = callFunction(board, address[name], args);
    assert.deepEqual([r0, r1].slice(0, expected.length), expected, name);
    assert.equal(read(0x78) & 3, 3, `${name}: ready and dirty again`);
    assert.deepEqual([read(0x74), read(0x70)], [1234567 % 89, Math.floor(1234567 / 89)], name);
  }
});

test("the memory routines (the ROM's) copy, fill and clear exactly the bytes asked", () => {
  // In SRAM bank 5 (0x20041000, outside the linker's RAM): a pattern, then each routine on a
  // range inside it, the bytes around it untouched.
  const BASE = 0x20041000;
  const SIZE = 96;
  const fill = () => {
    for (let k = 0; k < SIZE; k++) {
      board.mcu.writeUint8(BASE + k, (k * 7 + 1) & 0xff);
    }
  };
  const bytes = () => Array.from({ length: SIZE }, (_, k) => board.mcu.readUint8(BASE + k));
  /** @type {{name: string, aligned: boolean, args: (d: number, n: number) => number[], apply: (m: number[], d: number, n: number) => unknown}[]} */
  const cases = [
    {
      name: '__aeabi_memcpy',
      aligned: false,
      args: (d, n) => [BASE + d, BASE + 61, n],
      apply: (m, d, n) => m.splice(d, n, ...m.slice(61, 61 + n)),
    },
    {
      name: '__aeabi_memcpy4',
      aligned: true,
      args: (d, n) => [BASE + d, BASE + 60, n],
      apply: (m, d, n) => m.splice(d, n, ...m.slice(60, 60 + n)),
    },
    {
      name: '__aeabi_memset',
      aligned: false,
      args: (d, n) => [BASE + d, n, 0x1a5],
      apply: (m, d, n) => m.fill(0xa5, d, d + n),
    },
    {
      name: '__aeabi_memset4',
      aligned: true,
      args: (d, n) => [BASE + d, n, 0x3c],
      apply: (m, d, n) => m.fill(0x3c, d, d + n),
    },
    {
      name: '__aeabi_memclr',
      aligned: false,
      args: (d, n) => [BASE + d, n],
      apply: (m, d, n) => m.fill(0, d, d + n),
    },
    {
      name: '__aeabi_memclr4',
      aligned: true,
      args: (d, n) => [BASE + d, n],
      apply: (m, d, n) => m.fill(0, d, d + n),
    },
  ];
  for (const { name, aligned, args, apply } of cases) {
    for (const d of aligned ? [0, 4, 8] : [0, 1, 2, 3, 5]) {
      for (const n of [0, 1, 3, 4, 7, 8, 13, 32, 35]) {
        fill();
        const expected = bytes();
        apply(expected, d, n);
        callFunction(board, address[name], args(d, n));
        assert.deepEqual(bytes(), expected, `${name} at +${d}, ${n} bytes`);
      }
    }
  }
});

test('64-bit multiplication: the low 64 bits of the product', () => {
  const next = random(17);
  const word = () => BigInt(next());
  const wrong = [];
  const edges = [0n, 1n, 0xffffn, 0x10000n, 0xffffffffn, 0x100000000n, (1n << 64n) - 1n, 1n << 63n];
  const operands = [...edges];
  for (let i = 0; i < 5000; i++) {
    operands.push((word() << 32n) | word(), word(), BigInt.asUintN(64, -word()));
  }
  for (let i = 0; i < operands.length; i++) {
    const a = operands[i];
    const b = operands[(i * 7 + 3) % operands.length];
    const lo = (x) => Number(x & 0xffffffffn);
    const hi = (x) => Number(x >> 32n);
    const { r0, r1 } = callFunction(board, address.__aeabi_lmul, [lo(a), hi(a), lo(b), hi(b)]);
    const expected = BigInt.asUintN(64, a * b);
    if (r0 !== lo(expected) || r1 !== hi(expected)) {
      wrong.push(`${a} * ${b}`);
    }
  }
  for (const a of edges) {
    for (const b of edges) {
      const { r0, r1 } = callFunction(board, address.__aeabi_lmul, [
        Number(a & 0xffffffffn),
        Number(a >> 32n),
        Number(b & 0xffffffffn),
        Number(b >> 32n),
      ]);
      const expected = BigInt.asUintN(64, a * b);
      if ((BigInt(r1) << 32n) + BigInt(r0) !== expected) {
        wrong.push(`${a} * ${b}`);
      }
    }
  }
  assert.deepEqual(wrong.slice(0, 10), [], `${wrong.length} differ`);
});
