#!/usr/bin/env python3
"""The lab lift's PLC program, small, in Python, over Modbus TCP.

Start the rig without its own controller, then this program beside it:

    asi-lift serve fifo --controller external --speed max --until 120s
    python examples/controller.py                 # --host 127.0.0.1 --port 5020

It runs the three nibble handshakes of the lab bus (book/src/handshakes.md), finds
floor 1 (docs/controller.md §5.1), then serves the calls as the lift thesis' FIFO control does
(§5.3): cabin calls in the order pressed, then hall calls in the order pressed. It stops when
the server ends the run. What it leaves out: the book, "A controller in Python".
"""

import argparse
import sys
import time

from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ModbusException

# The gateway's registers (the book, "The gateway's register map").
TIME = 1050         # input registers 1050..1053: simulated ms, high word first; 1054: safety bits
ESTOP_OK = 1        # safety bit 0, EStopOut: 1 = the STOP circuit runs (no STOP demand)
SIGNALS = 1000      # holding register: bit 0 restart of the STOP circuit, bit 1 overloaded
SETPOINT = 68       # holding register: speed set-point in µA (slave 10, channel 1)
F0_F1 = 0x3000      # input word 0: flags F0 configuration error, F1 AS-i power fail

# The lab's slaves (lab/src/address.rs) and set-points in µA (controller/src/program/config.rs).
FLOORS = 4                      # floor stations at addresses 1..4
CABIN_DISPLAY, CABIN_PANEL, CONVERTER, LOAD_SENSOR = 5, 6, 7, 8
STANDSTILL, CREEP, TRAVEL, INIT = 4000, 6000, 10000, 11000
SCAN_MS = 10                    # the PLC scan (docs/controller.md)
DWELL_MS = 2000                 # the cabin stands 2 s at a floor before it departs (§5.3)

# Step codes of the handshakes (tables 4.3, 4.5, 4.7 of the lift thesis).
FOUR_STEPS = [0b111, 0b010, 0b001, 0b000]
SEVEN_STEPS = [0b111, 0b101, 0b100, 0b011, 0b010, 0b001, 0b000]
HALL_UP, HALL_DOWN, HALL_BOTH = 0b101, 0b100, 0b011


def nibble(words, a):
    """Slave a's 4 bits: four slaves per word, the lowest address in the highest bits."""
    return words[a // 4] >> (12 - 4 * (a % 4)) & 0xF


def set_nibble(words, a, v):
    shift = 12 - 4 * (a % 4)
    words[a // 4] = (words[a // 4] & ~(0xF << shift) | v << shift) & 0xFFFF


def display_word(floor, up=False, down=False, moving=False):
    """D10..D1 (table 4.2 of the lift thesis): floor, up, down, moving, fault, even parity."""
    w = floor << 5 | up << 4 | down << 3 | moving << 2
    return w | bin(w).count("1") % 2


class Answerer:
    """The PLC's side of a handshake the slave leads: floor stations (table 4.3, 4 steps)
    and cabin display (table 4.5, 7 steps). On every new step code the PLC answers 3 bits of
    the word and toggles K (D3). Codes outside the sequence (sync 110, a floor's buttons)
    get K toggled and 000."""

    def __init__(self, steps, transport):
        self.steps, self.transport = steps, transport
        self.code, self.k, self.data, self.bits = None, 0, 0, 0

    def step(self, inp, word):
        """Returns the output nibble and the code, if it is new (else None)."""
        code = inp & 7
        if code == self.code:
            return self.k << 3 | self.data, None
        self.code, self.k = code, self.k ^ 1
        if code in self.steps:
            i = self.steps.index(code)
            if i == 0:          # a new word: take the display word now, for all its steps
                self.bits = self.transport(word)
            self.data = self.bits >> 3 * (len(self.steps) - 1 - i) & 7
        else:
            self.data = 0
        return self.k << 3 | self.data, code


def floor_transport(word):      # table 4.3: D10..D1, O = 0, V = 1
    return word << 2 | 0b01


def cabin_transport(word):      # table 4.5: E = 001, D16..D1 (the word in D10..D1), O, V
    return 0b001 << 18 | word << 2 | 0b01


class CabinPanel:
    """The PLC's side of the cabin buttons and sensors (tables 4.6, 4.7): the PLC requests
    "K 1 1 1", "K 1 0 1", ... with K toggling at every step, the slave echoes K on D3 with
    3 data bits. Two 21-bit halves E = 000 (floors 16..1) and E = 001 (sensors) make a word."""

    def __init__(self):
        self.reset()

    def reset(self):    # start a word with the K that differs from the slave's D3
        self.k, self.pos, self.acc, self.stall, self.half0 = None, 0, 0, 0, None

    def step(self, inp):
        """Returns the output nibble and a new good word (a dict), or None."""
        word = None
        echo = inp >> 3
        if self.k is None:
            self.k = echo ^ 1
        elif echo != self.k:
            self.stall += 1
            if self.stall >= 25:        # no echo for 250 ms: start a new word, K toggled
                self.stall, self.pos, self.acc, self.k = 0, 0, 0, self.k ^ 1
        else:
            self.stall, self.k = 0, self.k ^ 1
            self.acc, self.pos = self.acc << 3 | inp & 7, self.pos + 1
            if self.pos == 7:
                word = self.half(self.acc)
                self.pos, self.acc = 0, 0
        return self.k << 3 | SEVEN_STEPS[self.pos], word

    def half(self, bits):
        e, d, ov = bits >> 18, bits >> 2 & 0xFFFF, bits & 0b11
        if ov == 0b01 and e == 0:
            self.half0 = d
            return None
        h0, self.half0 = self.half0, None
        if ov != 0b01 or e != 1 or h0 is None:
            return None
        if (bin(h0).count("1") + bin(d).count("1")) % 2 or d >> 14:   # D14 parity
            return None
        return {"buttons": h0 | (d & 0xFF) << 16, "left": bool(d >> 8 & 1),
                "right": bool(d >> 9 & 1), "stop": bool(d >> 10 & 1),
                "door_closed": bool(d >> 12 & 1)}


class Lift:
    """Initialisation and the FIFO control over the handshakes' words (docs/controller.md)."""

    def __init__(self):
        self.stations = [Answerer(FOUR_STEPS, floor_transport) for _ in range(FLOORS)]
        self.display = Answerer(SEVEN_STEPS, cabin_transport)
        self.panel, self.bus_ok = CabinPanel(), True
        self.cabin, self.cabin_at = None, None
        self.cabin_calls, self.hall_calls = [], []      # FIFO_Kabina, FIFO_Patra (§5.2)
        self.state, self.floor, self.pos, self.target, self.dir = "wait", 1, 1, 1, 0
        self.depart_at, self.restart_wanted, self.restart_high, self.next_restart = 0, True, False, 0

    def log(self, now, text):
        print(f"{now / 1000:8.3f} s  {text}", flush=True)

    def call(self, now, fifo, floor, source):
        if floor not in fifo:   # a floor already queued is not queued again (§5.2)
            fifo.append(floor)
            self.log(now, f"{source} call {floor}")

    def scan(self, now, inp, safety):
        """One scan: the input words 0..2 in; output words 0..2, set-point, signals out."""
        out = [0, 0, 0]
        moving = self.state in ("travel", "creep") or self.state.startswith("init")
        shown = display_word(self.floor, self.dir > 0, self.dir < 0, moving)
        for f in range(1, FLOORS + 1):              # floor stations, table 4.3
            n, code = self.stations[f - 1].step(nibble(inp, f), shown)
            set_nibble(out, f, n)
            if code in (HALL_UP, HALL_DOWN, HALL_BOTH):
                self.call(now, self.hall_calls, f, "hall")
        set_nibble(out, CABIN_DISPLAY, self.display.step(nibble(inp, CABIN_DISPLAY), shown)[0])
        if ((inp[0] & F0_F1) == 0) != self.bus_ok:    # a slave left or joined: new cabin word
            self.bus_ok = not self.bus_ok
            self.panel.reset()
        n, word = self.panel.step(nibble(inp, CABIN_PANEL))
        set_nibble(out, CABIN_PANEL, n)
        old = self.cabin
        if word:
            self.cabin, self.cabin_at = word, now
            pressed = word["buttons"] & ~(old["buttons"] if old else 0)
            for f in range(1, FLOORS + 1):
                if pressed >> (f - 1) & 1:
                    self.call(now, self.cabin_calls, f, "cabin")
                    if not safety & ESTOP_OK:       # a cabin call ends a STOP (§5.4)
                        self.restart_wanted = True
        load = nibble(inp, LOAD_SENSOR)             # D1..D0 load, D2 "ready"
        overloaded = (load & 3) == 3 or not load & 4
        # The STOP circuit's restart: a one-scan pulse every 500 ms, after power-on and after
        # a STOP once a cabin call came, until EStopOut says the circuit runs (§5.4).
        if safety & ESTOP_OK:
            self.restart_wanted = False
        if self.restart_high:
            self.restart_high = False
        elif self.restart_wanted and now >= self.next_restart:
            self.restart_high, self.next_restart = True, now + 500
        signals = self.restart_high | overloaded << 1
        run, up, ua = self.control(now, old, word, safety, overloaded)
        set_nibble(out, CONVERTER, run | up << 1)
        return out, (ua if run else STANDSTILL), signals

    def control(self, now, old, word, safety, overloaded):
        """The motion: returns run, up, set-point."""
        c = self.cabin
        if c is None:
            return False, False, STANDSTILL
        # Never move with the door open, overloaded, under STOP or without fresh cabin words.
        if (c["stop"] or not c["door_closed"] or overloaded or not safety & ESTOP_OK
                or now - self.cabin_at > 1000):
            return False, False, STANDSTILL
        left, right = c["left"], c["right"]
        was = (old["left"], old["right"]) if old and word else (left, right)
        entered = (left or right) and not any(was)          # a vane's first edge
        level = left and right                              # both sensors: level at a floor
        s = self.state
        # Initialisation (table 6.3, with the starts asi-lift adds, controller/src/program/
        # init.rs): floor 1's vane is turned, so only there the left sensor's track is long.
        if s == "wait":
            s = {(True, True): "init-probe", (True, False): "init-down"}.get((left, right), "init-run")
            self.log(now, f"initialisation: {s}")
        if s == "init-probe" and not right and left:        # floor 1: just below its level
            s = "init-up"
        elif s == "init-probe" and not left:                # another floor: run down
            s = "init-run"
        elif s == "init-run" and left and not was[0] and not right:   # floor 1's long track
            s = "init-down"
        elif s == "init-down" and not left:                 # below floor 1's vane
            s = "init-up"
        elif s in ("init-down", "init-up") and level:
            self.log(now, "at floor 1: initialised")
            self.floor = self.pos = self.target = 1
            s, self.depart_at = "idle", now + DWELL_MS
        # The automat (tables 6.4, 6.5): depart, count the vanes, creep in the target's vane,
        # stop level.
        if s == "idle" and now >= self.depart_at and (self.cabin_calls or self.hall_calls):
            self.target = (self.cabin_calls or self.hall_calls)[0]
            if self.target == self.floor:
                self.arrive(now)
            else:
                self.dir = 1 if self.target > self.floor else -1
                s = "travel"
                self.log(now, f"departs from floor {self.floor} to {self.target}")
        elif s == "travel" and entered:
            self.pos += self.dir
            if self.pos == self.target:
                s = "creep"
        elif s == "creep" and level:
            s = "idle"
            self.arrive(now)
        self.state = s
        return {
            "init-probe": (True, False, CREEP), "init-down": (True, False, CREEP),
            "init-up": (True, True, CREEP), "init-run": (True, False, INIT),
            "travel": (True, self.dir > 0, TRAVEL), "creep": (True, self.dir > 0, CREEP),
        }.get(s, (False, False, STANDSTILL))

    def arrive(self, now):
        """Stop level at the target: every call waiting there is served (§5.3)."""
        self.floor = self.pos = self.target
        self.dir, self.depart_at = 0, now + DWELL_MS
        self.cabin_calls = [f for f in self.cabin_calls if f != self.floor]
        self.hall_calls = [f for f in self.hall_calls if f != self.floor]
        self.log(now, f"level at floor {self.floor}")


def ok(r):
    if r.isError():
        raise ModbusException(f"the gateway answered {r}")
    return r


def run(client, on_scan=None):
    """Scans every 10 ms of simulated time until the server ends the run; returns the
    number of scans. on_scan(now), if given, runs after each scan (the check script's)."""
    lift, next_scan, scans, last = Lift(), 0, 0, None
    try:
        while True:
            w = ok(client.read_input_registers(TIME, count=5)).registers
            now = w[0] << 48 | w[1] << 32 | w[2] << 16 | w[3]
            if now < next_scan:
                if now == last:             # at --speed 1 or so: let the wall clock go on
                    time.sleep(0.001)
                last = now
                continue
            inp = ok(client.read_input_registers(0, count=3)).registers
            out, ua, signals = lift.scan(now, inp, w[4])
            ok(client.write_registers(0, out))
            ok(client.write_register(SETPOINT, ua))
            ok(client.write_register(SIGNALS, signals))
            scans, next_scan = scans + 1, now + SCAN_MS
            if on_scan:
                on_scan(now)
    except (ModbusException, ConnectionError, OSError) as e:
        print(f"the run has ended ({e})", flush=True)
    return scans


def connect(host, port, wait_s=10.0):
    client = ModbusTcpClient(host, port=port, timeout=5)
    deadline = time.monotonic() + wait_s
    while not client.connect():
        if time.monotonic() > deadline:
            sys.exit(f"cannot connect to {host}:{port}: is `asi-lift serve` running?")
        time.sleep(0.2)
    return client


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=5020)
    a = ap.parse_args()
    client = connect(a.host, a.port)
    start = time.monotonic()
    scans = run(client)
    client.close()
    print(f"{scans} scans in {time.monotonic() - start:.1f} s of wall time")


if __name__ == "__main__":
    main()
