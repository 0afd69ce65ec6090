#!/usr/bin/env python3
"""The s7commplus package's client (PyPI 0.3.0, MIT) polling names, for `npm run bench`.

bench/run.js starts this script with the venv's Python (test/interop/.venv-s7commplus)
and gives it one JSON job on stdin:
  {host, port, fingerprint, names: [...], warmMs, durationMs,
   proxyPort (optional), countPolls (optional)}
It connects over TLS pinned to the fingerprint and reads all `names` with
read_tags() (the package's own API: one call per poll, split over requests
as the package splits them), then prints one JSON line per step:
  {"event": "first", "values": {name: the package's decoding, or an error}}
  {"event": "timed", "polls": N, "elapsedMs": ms, "cpuMs": ms}
      polls in `durationMs` after `warmMs` of warm-up; cpuMs is the user +
      system CPU time of this process during them (time.process_time())
  {"event": "counting"}  (a second connection, through the proxy at proxyPort;
      then it waits for a line on stdin, the proxy having been reset)
  {"event": "counted", "polls": countPolls}
or {"event": "error", "type": ..., "message": ...} and exit 1.
"""

import json
import sys
import time

from s7commplus import Client


def emit(obj):
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


def connect(job, port):
    client = Client()
    client.connect(job.get("host", "127.0.0.1"), port, use_tls=True, tls_cert_fingerprint=job["fingerprint"])
    return client


def decoded(result):
    if result.error is not None or result.value is None:
        return {"error": str(result.error)}
    value = result.tag.decode_value(result.value)
    if isinstance(value, (bytes, bytearray)):
        return bytes(value).hex()
    return value


def main():
    job = json.loads(sys.stdin.readline())
    names = list(job["names"])
    client = connect(job, int(job["port"]))
    try:
        first = client.read_tags(names)  # browses the PLC once (the package's tag catalog)
        emit({"event": "first", "values": {r.tag.name: decoded(r) for r in first}})
        warm_until = time.monotonic() + job.get("warmMs", 300) / 1000
        while time.monotonic() < warm_until:
            client.read_tags(names)
        cpu0 = time.process_time()
        t0 = time.perf_counter()
        until = time.monotonic() + job["durationMs"] / 1000
        polls = 0
        while time.monotonic() < until:
            client.read_tags(names)
            polls += 1
        elapsed = time.perf_counter() - t0
        cpu = time.process_time() - cpu0
        emit({"event": "timed", "polls": polls, "elapsedMs": elapsed * 1000, "cpuMs": cpu * 1000})
    finally:
        client.disconnect()
    if job.get("proxyPort") and job.get("countPolls"):
        client = connect(job, int(job["proxyPort"]))
        try:
            client.read_tags(names)  # the browse, before counting
            emit({"event": "counting"})
            sys.stdin.readline()
            for _ in range(int(job["countPolls"])):
                client.read_tags(names)
            emit({"event": "counted", "polls": int(job["countPolls"])})
        finally:
            client.disconnect()
    return 0


if __name__ == "__main__":
    try:
        code = main()
    except Exception as e:  # reported to the benchmark, which prints it in the table
        emit({"event": "error", "type": type(e).__name__, "message": str(e)})
        code = 1
    sys.exit(code)
