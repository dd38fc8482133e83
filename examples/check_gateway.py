#!/usr/bin/env python3
"""Checks the gateway's images and lists against the bus trace of the same run.

Starts `asi-lift serve SCENARIO --controller external --speed max --trace T.jsonl` on a free
loopback port, drives it with examples/controller.py, and every --every ms of simulated time
reads the input image (input registers 0..15), LAS (input registers 1000..1003 and discrete
inputs 256..319) and simulated time. After the run it compares them with the trace:

- each slave's input nibble read at simulated time t is the data of that slave's last
  Data_Exchange with a response in the trace that ended at or before t (the master writes
  the image when a transaction ends: 154 µs after its first pulse on a clean line; at
  --speed max with one client each request is served at the time it reads, then the
  simulation advances 1 ms, so the moments are exact);
- LAS holds exactly the lab's slaves (1..8, 10, 11, 12), as bits and as registers, and each
  of them was activated in the trace before the read.

Prints every mismatch (the first 50) and exits 1 on any, or if the run itself fails.
"""

import argparse
import bisect
import json
import os
import re
import subprocess
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import controller  # noqa: E402  (examples/controller.py)

LAB = [1, 2, 3, 4, 5, 6, 7, 8, 10, 11, 12]     # lab/src/address.rs
TRANSACTION_NS = 154_000                         # asi-phy/src/timing.rs: 84 + 18 + 42 + 10 µs


def milliseconds(d):
    """A duration as asi-lift writes them ("30s", "1.5min", "250ms") in ms."""
    m = re.fullmatch(r"([0-9.]+)\s*(ms|s|min|h)", d)
    if not m:
        sys.exit(f"check: --until {d}: expected a number and ms, s, min or h")
    return float(m.group(1)) * {"ms": 1, "s": 1000, "min": 60_000, "h": 3_600_000}[m.group(2)]


def start_serve(args, tmp):
    """Runs serve in the background; returns the process and its port."""
    err = open(os.path.join(tmp, "serve.err"), "w+")
    cmd = [args.asi_lift, "serve", args.scenario, "--controller", "external",
           "--speed", "max", "--until", args.until, "--listen", "127.0.0.1:0",
           "--trace", os.path.join(tmp, "trace.jsonl"),
           "--report", os.path.join(tmp, "report.json"), "--format", "json"]
    proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=err)
    deadline = time.monotonic() + 30
    while time.monotonic() < deadline:      # serve says where it listens on standard error
        err.seek(0)
        m = re.search(r"gateway on 127\.0\.0\.1:(\d+)", err.read())
        if m:
            return proc, int(m.group(1))
        if proc.poll() is not None:
            break
        time.sleep(0.05)
    proc.kill()
    err.seek(0)
    sys.exit(f"check: asi-lift serve did not start:\n{err.read()}")


def sample(client):
    """Five requests at t, t+1, ..., t+4 ms: time, image, LAS registers, LAS bits, time."""
    def regs(a, n):
        return controller.ok(client.read_input_registers(a, count=n)).registers
    w = regs(controller.TIME, 4)
    t = w[0] << 48 | w[1] << 32 | w[2] << 16 | w[3]
    image = regs(0, 16)
    las_regs = regs(1000, 4)
    las_bits = controller.ok(client.read_discrete_inputs(256, count=64)).bits[:64]
    w = regs(controller.TIME, 4)
    t4 = w[0] << 48 | w[1] << 32 | w[2] << 16 | w[3]
    return {"t": t, "image": image, "image_at": t + 1, "las_regs": las_regs,
            "las_bits": las_bits, "t4": t4}


def read_trace(path):
    """Per A-slave address: [(end of transaction ns, data nibble)] of the Data_Exchanges
    with a response; and the first activation's end per address."""
    ends, activated = {}, {}
    with open(path) as f:
        for line in f:
            e = json.loads(line)
            req, resp = e["request"], e["response"]
            if req["call"] != "Data_Exchange" or resp is None:
                continue
            if e["phase"] not in ("data", "activate"):
                continue
            a, end = req["address"], e["t_ns"] + TRANSACTION_NS
            ends.setdefault(a, []).append((end, int(resp["data"], 2)))
            if e["phase"] == "activate":
                activated.setdefault(a, end)
    return ends, activated


def expected_nibble(ends, a, t_ns):
    """The data of slave a's last exchange that ended at or before t_ns (0000 if none)."""
    ex = ends.get(a, [])
    i = bisect.bisect_right(ex, (t_ns, 0xF))
    return ex[i - 1][1] if i else 0


def compare(samples, ends, activated):
    errors = []
    las_expected = sum(1 << a for a in LAB)
    for s in samples:
        t = s["image_at"]
        if s["t4"] != s["t"] + 4:
            errors.append(f"t={s['t']} ms: not in lockstep: the fifth request read {s['t4']} ms")
        for a in range(1, 32):      # slot 0 holds the flags F0..F3, not a slave
            got = controller.nibble(s["image"], a)
            want = expected_nibble(ends, a, t * 1_000_000)
            if got != want:
                errors.append(f"t={t} ms: slave {a}: input image {got:04b}, "
                              f"trace {want:04b} (last Data_Exchange ending at or before t)")
        for w in range(8, 16):      # B slaves: the lab has none
            if s["image"][w]:
                errors.append(f"t={t} ms: input word {w} (B slaves) is {s['image'][w]:#06x}")
        regs = s["las_regs"]
        las = regs[0] | regs[1] << 16
        bits = sum(1 << n for n, b in enumerate(s["las_bits"]) if b)
        if las != las_expected or regs[2] or regs[3]:
            errors.append(f"t={s['t'] + 2} ms: LAS registers {regs}, expected the lab's slaves {LAB}")
        if bits != las_expected:
            errors.append(f"t={s['t'] + 3} ms: LAS bits {bits:#x}, expected {las_expected:#x}")
        late = [a for a in LAB if activated.get(a, float("inf")) > (s["t"] + 2) * 1_000_000]
        if late:
            errors.append(f"t={s['t'] + 2} ms: LAS holds slaves {late} the trace has not activated")
    return errors


def main():
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    ap = argparse.ArgumentParser(description="Check the gateway against the bus trace.")
    ap.add_argument("--asi-lift", default=os.path.join(root, "target/release/asi-lift"))
    ap.add_argument("--scenario", default="fifo")
    ap.add_argument("--until", default="30s")
    ap.add_argument("--every", type=int, default=1000, help="ms of simulated time between reads")
    ap.add_argument("--from", dest="first", type=int, default=1000,
                    help="first read at this simulated ms (the bus is up by then)")
    args = ap.parse_args()

    with tempfile.TemporaryDirectory(prefix="check-gateway-") as tmp:
        proc, port = start_serve(args, tmp)
        samples, due, end_ms = [], [args.first], milliseconds(args.until)

        def on_scan(now):
            if due[0] <= now < end_ms - 10:     # five requests, all before the run's end
                samples.append(sample(client))
                due[0] = now + args.every

        try:
            client = controller.connect("127.0.0.1", port)
            controller.run(client, on_scan)
            client.close()
            proc.wait(timeout=120)
        finally:
            if proc.poll() is None:
                proc.kill()
        if proc.returncode != 0:
            with open(os.path.join(tmp, "serve.err")) as err:
                sys.exit(f"check: asi-lift serve exited with {proc.returncode}:\n{err.read()}")
        ends, activated = read_trace(os.path.join(tmp, "trace.jsonl"))
        errors = compare(samples, ends, activated)
    for e in errors[:50]:
        print("check:", e)
    if not samples:
        sys.exit("check: no samples taken")
    if errors:
        sys.exit(f"check: {len(errors)} mismatches in {len(samples)} reads")
    print(f"check: {len(samples)} reads from {samples[0]['t']} to {samples[-1]['t']} ms: "
          f"input image and LAS agree with the trace ({sum(map(len, ends.values()))} Data_Exchanges)")


if __name__ == "__main__":
    main()
