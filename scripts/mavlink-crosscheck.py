#!/usr/bin/env python3
"""The monitor's MAVLink read by a MAVLink library of the ecosystem (docs/telemetry.md).

Installs node-mavlink (ArduPilot/node-mavlink on npm, pinned) into a scratch directory, replays
logs with `battsim replay --estimator joint --mavlink`, and decodes each stream twice. Once with
node-mavlink, which drops frames whose checksum is wrong. Once with this script's own decoder.
Then it compares the two: frames per message id, every BATTERY_STATUS field, every
STATUSTEXT. It also flips one byte of a copy and checks that node-mavlink drops that frame.
Needs node and npm with access to the npm registry; not part of the test command.

    python3 scripts/mavlink-crosscheck.py [LOG ...] [-c CONFIG]

Without LOGs: the dissertation's four flights and the bundled example.
"""
import argparse
import json
import os
import struct
import subprocess
import sys
import tempfile

from mavlink_stream import BATTERY_STATUS, frames, text

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BATTSIM = os.path.join(ROOT, "build", "battsim")
DATA = os.environ.get("BATTSIM_DATA_DIR", os.path.join(ROOT, "..", "shared", "data"))
NODE_MAVLINK = "node-mavlink@2.3.0"

# Reads a stream with node-mavlink and prints what it found as JSON.
NODE_READER = r"""
const { createReadStream } = require('node:fs')
const { createMavLinkStream, minimal, common } = require('node-mavlink')
const REGISTRY = { ...minimal.REGISTRY, ...common.REGISTRY }
const out = { ids: {}, battery: [], texts: [] }
createMavLinkStream(createReadStream(process.argv[2]))
  .on('data', p => {
    out.ids[p.header.msgid] = (out.ids[p.header.msgid] || 0) + 1
    const d = p.protocol.data(p.payload, REGISTRY[p.header.msgid])
    if (p.header.msgid === 147)
      out.battery.push([d.currentConsumed, d.energyConsumed, d.temperature, ...d.voltages, d.currentBattery, d.id,
                        d.batteryFunction, d.type, d.batteryRemaining, d.timeRemaining, d.chargeState,
                        ...d.voltagesExt, d.mode, d.faultBitmask])
    if (p.header.msgid === 253) out.texts.push([d.severity, d.text])
  })
  .on('end', () => console.log(JSON.stringify(out)))
"""

def own_reading(data):
    out = {"ids": {}, "battery": [], "texts": []}
    for _, msgid, p in frames(data):
        out["ids"][str(msgid)] = out["ids"].get(str(msgid), 0) + 1
        if msgid == 147:
            out["battery"].append(list(struct.unpack_from(BATTERY_STATUS, p)))
        if msgid == 253:
            out["texts"].append([p[0], text(p)])
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("logs", nargs="*")
    ap.add_argument("-c", "--config", default=os.path.join(ROOT, "configs", "sim-4s.json"))
    a = ap.parse_args()
    logs = a.logs or [os.path.join(DATA, "predictive-bms", "flights", "%d.csv" % n) for n in (29, 30, 32, 34)] + [
        os.path.join(ROOT, "logs", "example-4s.csv")]
    failed = False
    with tempfile.TemporaryDirectory() as tmp:
        subprocess.run(["npm", "init", "-y"], cwd=tmp, check=True, capture_output=True)
        r = subprocess.run(["npm", "install", "--no-audit", "--no-fund", NODE_MAVLINK], cwd=tmp, capture_output=True, text=True)
        if r.returncode != 0:
            sys.exit("mavlink-crosscheck: npm install %s failed:\n%s" % (NODE_MAVLINK, r.stderr))
        reader = os.path.join(tmp, "read.cjs")
        open(reader, "w").write(NODE_READER)
        for log in logs:
            stream = os.path.join(tmp, "out.mavlink")
            subprocess.run([BATTSIM, "replay", log, "-c", a.config, "--estimator", "joint", "--mavlink", stream],
                           check=True, capture_output=True)
            data = open(stream, "rb").read()
            theirs = json.loads(subprocess.run(["node", reader, stream], cwd=tmp, check=True, capture_output=True, text=True).stdout)
            ours = own_reading(data)
            same = theirs == ours
            bad = bytearray(data)
            bad[40] ^= 1  # inside the first BATTERY_STATUS
            open(stream, "wb").write(bad)
            dropped = json.loads(subprocess.run(["node", reader, stream], cwd=tmp, check=True, capture_output=True,
                                                text=True).stdout)["ids"].get("147", 0) == ours["ids"]["147"] - 1
            failed |= not (same and dropped)
            print("%s: %d frames (%s), %d texts; node-mavlink reads the same: %s; drops a corrupted frame: %s" % (
                os.path.basename(log), sum(ours["ids"].values()),
                ", ".join("id %s × %d" % kv for kv in sorted(ours["ids"].items(), key=lambda kv: int(kv[0]))),
                len(ours["texts"]), "yes" if same else "NO", "yes" if dropped else "NO"))
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
