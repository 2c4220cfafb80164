#!/usr/bin/env bash
# Line and region coverage of the code under test (control/, kinematics-core/) reached by
# each fuzz target's corpus (the committed seeds plus fuzz/corpus/, which `./dev fuzz`
# grows). Replays the inputs through the same checks on stable Rust with -Cinstrument-coverage
# and summarises with llvm-cov. Needs `rustup component add llvm-tools`. Not part of CI.
# Usage: fuzz/coverage.sh [TARGET...]
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."

sysroot=$(rustc --print sysroot)
host=$(rustc -vV | sed -n 's/^host: //p')
tools="$sysroot/lib/rustlib/$host/bin"
[[ -x $tools/llvm-cov ]] || { echo "needs: rustup component add llvm-tools" >&2; exit 2; }

targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(protocol command number settings controller)
out=fuzz/target/coverage
rm -rf "$out/profiles"
mkdir -p "$out/profiles"

export CARGO_TARGET_DIR=$out/build
# --target keeps the instrumentation off build scripts (they would leave .profraw files here).
RUSTFLAGS="-Cinstrument-coverage" cargo test -p robustness --test seeds --no-run --target "$host" \
    --message-format=json 2>/dev/null |
    sed -n 's/.*"executable":"\([^"]*\)".*/\1/p' | tail -n 1 >"$out/binary"
binary=$(cat "$out/binary")

declare -A own=([protocol]=protocol.rs [command]=command.rs [number]=number.rs
    [settings]=settings.rs [controller]=controller.rs)
# llvm-cov rows: name, regions, missed, cover, functions, missed, cover, lines, missed, cover.
row() { awk -v f="$1" '$1 ~ f { printf "%s of %s lines", $10, $8 }' "$2"; }

printf '%-11s  %-28s  %s\n' target "its own module" "all of control/ + kinematics-core/"
for target in "${targets[@]}"; do
    LLVM_PROFILE_FILE="$out/profiles/$target-%p.profraw" FUZZ_CORPUS=fuzz/corpus \
        "$binary" --exact "${target}_seeds" --quiet >/dev/null
    "$tools/llvm-profdata" merge -sparse "$out/profiles/$target"-*.profraw -o "$out/$target.profdata"
    "$tools/llvm-cov" report "$binary" -instr-profile="$out/$target.profdata" \
        -ignore-filename-regex='(\.cargo|rustc|robustness|/tests?/)' >"$out/$target.txt" 2>/dev/null
    printf '%-11s  %-28s  %s\n' "$target" "${own[$target]} $(row "control/src/${own[$target]}" "$out/$target.txt")" \
        "$(row '^TOTAL$' "$out/$target.txt")"
done
"$tools/llvm-profdata" merge -sparse "$out/profiles"/*.profraw -o "$out/all.profdata"
"$tools/llvm-cov" report "$binary" -instr-profile="$out/all.profdata" \
    -ignore-filename-regex='(\.cargo|rustc|robustness|/tests?/)' >"$out/all.txt" 2>/dev/null
printf '%-11s  %-28s  %s\n' "all" "" "$(row '^TOTAL$' "$out/all.txt")"
echo "(per file: $out/<target>.txt and $out/all.txt)"
