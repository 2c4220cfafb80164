// Minimal ELF32 reader: the firmware's loadable segments, placed at their load (physical)
// addresses, which is how a programmer writes them to flash (.data's initial values included).

import { readFileSync } from 'node:fs';

const PT_LOAD = 1;

/** @returns {{ address: number, bytes: Uint8Array }[]} PT_LOAD segments with file contents. */
export function loadSegments(elfPath) {
  const file = readFileSync(elfPath);
  const view = new DataView(file.buffer, file.byteOffset, file.byteLength);
  const isElf32LittleEndian =
    file.length >= 52 &&
    file[0] === 0x7f &&
    file[1] === 0x45 &&
    file[2] === 0x4c &&
    file[3] === 0x46 && // "\x7fELF"
    file[4] === 1 && // ELFCLASS32
    file[5] === 1; // ELFDATA2LSB
  if (!isElf32LittleEndian) {
    throw new Error(`${elfPath} is not a 32-bit little-endian ELF file`);
  }
  const programHeaderOffset = view.getUint32(0x1c, true);
  const programHeaderSize = view.getUint16(0x2a, true);
  const programHeaderCount = view.getUint16(0x2c, true);

  const segments = [];
  for (let i = 0; i < programHeaderCount; i++) {
    const header = programHeaderOffset + i * programHeaderSize;
    const type = view.getUint32(header, true);
    const offset = view.getUint32(header + 4, true);
    const physicalAddress = view.getUint32(header + 12, true);
    const fileSize = view.getUint32(header + 16, true);
    if (type === PT_LOAD && fileSize > 0) {
      segments.push({ address: physicalAddress, bytes: file.subarray(offset, offset + fileSize) });
    }
  }
  return segments;
}

const SHF_ALLOC = 0x2;

/** Sizes of the allocated sections (`.text`, `.rodata`, `.data`, `.bss`, ...), in bytes. */
export function sectionSizes(elfPath) {
  const file = readFileSync(elfPath);
  const view = new DataView(file.buffer, file.byteOffset, file.byteLength);
  const sectionHeaderOffset = view.getUint32(0x20, true);
  const sectionHeaderSize = view.getUint16(0x2e, true);
  const sectionCount = view.getUint16(0x30, true);
  const namesIndex = view.getUint16(0x32, true);
  const header = (i) => sectionHeaderOffset + i * sectionHeaderSize;
  const namesOffset = view.getUint32(header(namesIndex) + 0x10, true);
  const sizes = {};
  for (let i = 0; i < sectionCount; i++) {
    const flags = view.getUint32(header(i) + 0x08, true);
    const size = view.getUint32(header(i) + 0x14, true);
    if (!(flags & SHF_ALLOC) || size === 0) {
      continue;
    }
    let end = namesOffset + view.getUint32(header(i), true);
    const start = end;
    while (file[end] !== 0) {
      end++;
    }
    sizes[file.toString('latin1', start, end)] = size;
  }
  return sizes;
}

const SHT_SYMTAB = 2;

/** Every symbol in the ELF's symbol table: `[{ name, value, size }]` (raw names). */
function allSymbols(elfPath) {
  const file = readFileSync(elfPath);
  const view = new DataView(file.buffer, file.byteOffset, file.byteLength);
  const sectionHeaderOffset = view.getUint32(0x20, true);
  const sectionHeaderSize = view.getUint16(0x2e, true);
  const sectionCount = view.getUint16(0x30, true);
  const header = (i) => sectionHeaderOffset + i * sectionHeaderSize;
  const symbols = [];
  for (let i = 0; i < sectionCount; i++) {
    if (view.getUint32(header(i) + 0x04, true) !== SHT_SYMTAB) {
      continue;
    }
    const offset = view.getUint32(header(i) + 0x10, true);
    const size = view.getUint32(header(i) + 0x14, true);
    const entrySize = view.getUint32(header(i) + 0x24, true);
    const strings = view.getUint32(header(view.getUint32(header(i) + 0x18, true)) + 0x10, true);
    for (let entry = offset; entry < offset + size; entry += entrySize) {
      let end = strings + view.getUint32(entry, true);
      const start = end;
      while (file[end] !== 0) {
        end++;
      }
      symbols.push({
        name: file.toString('latin1', start, end),
        value: view.getUint32(entry + 4, true),
        size: view.getUint32(entry + 8, true),
      });
    }
  }
  return symbols;
}

/** The value of each named symbol in the ELF's symbol table (those asked for that exist). */
export function symbolValues(elfPath, names) {
  const wanted = new Set(names);
  const values = {};
  for (const { name, value } of allSymbols(elfPath)) {
    if (wanted.has(name)) {
      values[name] = value;
    }
  }
  return values;
}

/** Every symbol in the ELF's symbol table with a size: `[{ name, value, size }]` (raw names). */
export function sizedSymbols(elfPath) {
  return allSymbols(elfPath).filter(({ size }) => size > 0);
}

/** Sizes of the symbols whose (mangled) names `keep` accepts, by demangled-looking name. */
export function symbolSizes(elfPath, keep) {
  const sizes = {};
  for (const { name, size } of sizedSymbols(elfPath)) {
    if (keep(name)) {
      sizes[readableName(name)] = size;
    }
  }
  return sizes;
}

/**
 * The address ranges of the symbols whose (mangled) names `keep` accepts:
 * `[{ name, start, end }]` by demangled-looking name, `end` exclusive, Thumb bit cleared.
 */
export function symbolRanges(elfPath, keep) {
  return sizedSymbols(elfPath)
    .filter(({ name }) => keep(name))
    .map(({ name, value, size }) => {
      const address = value & ~1;
      return { name: readableName(name), start: address, end: address + size };
    });
}

/** `_ZN8firmware5flash10BOOT2_COPY17h...E` -> `firmware::flash::BOOT2_COPY`. */
function readableName(mangled) {
  const parts = [];
  let at = mangled.startsWith('_ZN') ? 3 : -1;
  while (at >= 0 && at < mangled.length && /\d/.test(mangled[at])) {
    let digits = '';
    while (/\d/.test(mangled[at])) {
      digits += mangled[at++];
    }
    const part = mangled.slice(at, at + Number(digits));
    at += Number(digits);
    if (!/^h[0-9a-f]{16}$/.test(part)) {
      parts.push(part);
    }
  }
  return parts.length > 0 ? parts.join('::') : mangled;
}
