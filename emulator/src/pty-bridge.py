#!/usr/bin/env python3
"""Pseudo-terminal bridge for the emulator's serial ports (Node has no pty support built in).

Opens a pty pair, prints the path of its terminal side on the first line of stdout, then
relays bytes: what a program (picocom, screen, a host tool) writes to that terminal comes
out on our stdout; what arrives on our stdin goes to that program. The terminal side starts
in raw mode (no echo, no CR/LF translation), like a USB serial adapter. Output nobody reads
is dropped once the pty's buffer is full, as on a real serial line with nothing attached.
Exits when stdin closes (the emulator ended).
"""

import os
import select
import sys
import tty


def main() -> None:
    # `terminal` stays open for as long as we run: without our own handle on it, reading the
    # controller side fails with EIO between one client closing the port and the next opening.
    controller, terminal = os.openpty()
    tty.setraw(terminal)
    os.set_blocking(controller, False)
    stdin = sys.stdin.fileno()
    stdout = sys.stdout.fileno()
    os.write(stdout, f"{os.ttyname(terminal)}\n".encode())
    while True:
        readable, _, _ = select.select([controller, stdin], [], [])
        if controller in readable:
            try:
                data = os.read(controller, 4096)
            except BlockingIOError:
                data = b""
            if data:
                os.write(stdout, data)
        if stdin in readable:
            data = os.read(stdin, 4096)
            if not data:
                return
            try:
                os.write(controller, data)
            except BlockingIOError:
                pass  # nobody is reading the port and its buffer is full


if __name__ == "__main__":
    try:
        main()
    except (BrokenPipeError, KeyboardInterrupt):
        pass
