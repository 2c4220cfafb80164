// Calls one function of the firmware on the emulated core, in place: the firmware stops where
// it is, the function runs with the arguments given (AAPCS: r0-r3) until it returns, and the
// core's registers are put back as they were. For routines that touch nothing but their
// arguments and registers (the float and division routines, emulator/test/intrinsics.test.js);
// interrupts are masked while it runs and emulated time does not advance.

/** Where the called function "returns" to: the call ends when the core is about to run it. */
const RETURN_ADDRESS = 0x20041f00;
/** More instructions than any routine called this way runs. */
const MAX_STEPS = 100_000;

/**
 * @param {import('./board.js').EmulatedBoard} board a booted board
 * @param {number} address the function's address (Thumb bit set or not)
 * @param {number[]} args up to four 32-bit arguments
 * @returns {{ r0: number, r1: number, cycles: number }} the results (unsigned) and the cycles
 *   the call took, from its first instruction to its return
 */
export function callFunction(board, address, args = []) {
  const { core } = board.mcu;
  const saved = {
    registers: core.registers.slice(),
    apsr: core.APSR,
    pm: core.PM,
    waiting: core.waiting,
  };
  args.forEach((value, k) => {
    core.registers[k] = value >>> 0;
  });
  core.PM = true;
  core.waiting = false;
  core.LR = RETURN_ADDRESS | 1;
  core.PC = address & ~1;
  let cycles = 0;
  for (let steps = 0; core.PC !== RETURN_ADDRESS; steps++) {
    if (steps === MAX_STEPS) {
      throw new Error(`the call of 0x${address.toString(16)} did not return`);
    }
    cycles += core.executeInstruction();
  }
  const result = { r0: core.registers[0] >>> 0, r1: core.registers[1] >>> 0, cycles };
  core.registers.set(saved.registers);
  core.APSR = saved.apsr;
  core.PM = saved.pm;
  core.waiting = saved.waiting;
  return result;
}
