#!/usr/bin/env python3
"""Runs operations with the S7CommPlus client of the s7commplus package.

s7commplus (https://github.com/gijzelaerr/s7commplus, MIT) is a Python
S7CommPlus client written independently of plcwire, validated by its authors
on S7-1200, S7-1500 and PLCSIM Advanced. This script is ours: it calls that
client (its S7CommPlusClient) for the operations it reads on stdin and prints
what the client got, so a test can hold our server against it.
test/support/s7commplus-peer.ts drives it.

The job comes on stdin (never on the command line: it may carry a password),
in one of two forms:
  batch        one JSON list of operations; prints one line
               {"ok": true, "results": [...]} and exits 0, or at the first
               failure {"ok": false, "failed": index, "error": {...},
               "results": [the results before it]} and exits 1.
  interactive  one JSON operation a line; prints one line a result,
               {"ok": true, "result": ...} or {"ok": false, "error": {...}},
               and goes on. At the end of stdin it disconnects and exits 1 if
               any operation failed, else 0.
An error is {"type": the exception's class, "message": its text}.

Operations ({"op": NAME, ...}):
  connect          host, port (102), tls (false), fingerprint (SHA-256 hex of
                   the server's certificate to pin), ca (PEM path), password,
                   connectionType ("hmi", "es", "pg"), timeoutMs
                   -> {protocolVersion, tls, tlsVersion ("TLSv1.3", ...),
                   fingerprint, sessionId, protectionLevel}
  list_datablocks  -> [{name, number, rid, ...}]
  browse           -> the client's browse(): [{name, access_sequence, data_type,
                   offsets...}] (bytes as hex)
  refresh_if_changed -> the client's refresh_caches_if_program_changed(): true when
                   the block list or a type object's modification time changed
                   (the catalog then browsed again)
  read_tags        names: [...] -> [{name, ok, value (hex), decoded (the package's
                   own decoding: number, bool, text; dates and times as text), type, error}]
  write_tag        name, value (hex) -> null
  write_tags       values: {name: hex} -> [{name, ok, error}]
  write_values     values: {name: a JSON value}, encoded by the package for the
                   tag's type -> [{name, ok, error}]
  db_read          db, offset, size -> hex
  db_write         db, offset, data (hex) -> null
  get_cpu_state    -> "RUN" | "STOP" | "UNKNOWN"
  subscribe        items: [tag names or access sequences], cycleMs (100)
                   -> subscription id
  notification     subscription (id, optional), timeoutMs (5000): waits for one
                   notification -> {subscription, sequence, values: {index: hex},
                   decoded: {index: value}, errors: {index: code}}; when none
                   comes in time the connection is unusable: the error is
                   {"type": "Timeout"} and the script exits 1 at once
  disconnect       -> null
"""

import itertools
import json
import os
import sys
import threading

from s7commplus import Client


class Timeout(Exception):
    """No notification in time; a thread is still reading the socket, so the client must not be used again."""


def hexify(value):
    """A JSON-friendly copy: bytes as hex, tuples as lists, other objects as text."""
    if isinstance(value, (bytes, bytearray)):
        return bytes(value).hex()
    if isinstance(value, dict):
        return {str(k): hexify(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [hexify(v) for v in value]
    if value is None or isinstance(value, (bool, int, float, str)):
        return value
    return str(value)


def decoded(tag, raw):
    """The package's decoding of a tag's bytes, JSON-friendly; None where it has none."""
    if raw is None:
        return None
    try:
        return hexify(tag.decode_value(raw))
    except Exception:
        return None


def error_of(e):
    return {"type": type(e).__name__, "message": str(e)}


def alarm_of(a):
    """An s7commplus Alarm as JSON: what the package decoded, texts by LCID."""
    return {
        "id": a.cpu_alarm_id,
        "state": a.state,
        "name": a.name,
        "domain": a.domain,
        "sequenceCounter": a.sequence_counter,
        "timestamp": a.timestamp,
        "ackTimestamp": a.acknowledge_timestamp,
        "hmiInfo": a.hmi_info.hex(),
        "values": [v.hex() for v in a.associated_values],
        "texts": {
            str(int(lang)): {"alarm": t.alarm_text, "info": t.info_text, "additional": list(t.additional_texts)}
            for lang, t in a.texts.items()
        },
    }


class Runner:
    def __init__(self):
        self.client = Client()
        self.stuck = False

    def run(self, op):
        name = op.get("op")
        handler = getattr(self, "op_" + str(name), None)
        if handler is None:
            raise ValueError(f"unknown operation {name!r}")
        return handler(op)

    def op_connect(self, op):
        c = self.client
        c.connect(
            op.get("host", "127.0.0.1"),
            int(op.get("port", 102)),
            use_tls=bool(op.get("tls", False)),
            tls_ca=op.get("ca"),
            tls_cert_fingerprint=op.get("fingerprint"),
            password=op.get("password"),
            connection_type=op.get("connectionType"),
        )
        pin = c.peer_certificate_fingerprint()
        # The package keeps its TLS object private; its version is what was negotiated.
        tls_object = getattr(c._connection, "_ssl_object", None)
        return {
            "protocolVersion": int(c.protocol_version),
            "tls": bool(c.tls_active),
            "tlsVersion": tls_object.version() if tls_object is not None else None,
            "fingerprint": pin.hex() if pin else None,
            "sessionId": c.session_id,
            "protectionLevel": c.protection_level,
        }

    def op_list_datablocks(self, op):
        return hexify(self.client.list_datablocks())

    def op_browse(self, op):
        return hexify(self.client.browse())

    def op_refresh_if_changed(self, op):
        return bool(self.client.refresh_caches_if_program_changed())

    def op_read_tags(self, op):
        results = self.client.read_tags(list(op["names"]))
        return [
            {
                "name": r.tag.name,
                "ok": r.error is None,
                "value": r.value.hex() if r.value is not None else None,
                "decoded": decoded(r.tag, r.value),
                "type": getattr(r.tag.softdatatype, "name", str(r.tag.softdatatype)),
                "error": error_of(r.error) if r.error is not None else None,
            }
            for r in results
        ]

    def op_write_values(self, op):
        values = {name: self.client.resolve_tag(name).encode_value(v) for name, v in op["values"].items()}
        return self.op_write_tags({"values": {name: raw.hex() for name, raw in values.items()}})

    def op_write_tag(self, op):
        self.client.write_tag(op["name"], bytes.fromhex(op["value"]))
        return None

    def op_write_tags(self, op):
        values = {name: bytes.fromhex(v) for name, v in op["values"].items()}
        results = self.client.write_tags(values)
        return [
            {"name": r.tag.name, "ok": r.error is None, "error": error_of(r.error) if r.error is not None else None}
            for r in results
        ]

    def op_db_read(self, op):
        return self.client.db_read(int(op["db"]), int(op["offset"]), int(op["size"])).hex()

    def op_db_write(self, op):
        self.client.db_write(int(op["db"]), int(op["offset"]), bytes.fromhex(op["data"]))
        return None

    def op_get_cpu_state(self, op):
        return self.client.get_cpu_state()

    def op_subscribe(self, op):
        return self.client.create_subscription(list(op["items"]), cycle_ms=int(op.get("cycleMs", 100)))

    def op_notification(self, op):
        got = {}

        def receive():
            try:
                got["n"] = self.client.receive_subscription_notification(op.get("subscription"))
            except Exception as e:  # reported below
                got["e"] = e

        worker = threading.Thread(target=receive, daemon=True)
        worker.start()
        worker.join(int(op.get("timeoutMs", 5000)) / 1000)
        if worker.is_alive():
            self.stuck = True
            raise Timeout(f"no notification within {int(op.get('timeoutMs', 5000))} ms")
        if "e" in got:
            raise got["e"]
        n = got["n"]
        return {
            "subscription": n.subscription_id,
            "sequence": n.sequence_number,
            "values": hexify(n.values),
            "decoded": hexify(n.decoded_values),
            "errors": hexify(n.errors),
        }

    # Alarms (issue #33): the package's alarm subscription, its notifications and the active-alarm list.
    def op_alarm_subscribe(self, op):
        return self.client.create_alarm_subscription(language_ids=op.get("languages"))

    def op_alarm_notification(self, op):
        got = {}

        def receive():
            try:
                got["n"] = self.client.receive_alarm_notification(op.get("languages"))
            except Exception as e:  # reported below
                got["e"] = e

        worker = threading.Thread(target=receive, daemon=True)
        worker.start()
        worker.join(int(op.get("timeoutMs", 5000)) / 1000)
        if worker.is_alive():
            self.stuck = True
            raise Timeout(f"no alarm notification within {int(op.get('timeoutMs', 5000))} ms")
        if "e" in got:
            raise got["e"]
        n = got["n"]
        return {"subscription": n.subscription_id, "sequence": n.sequence_number, "alarms": [alarm_of(a) for a in n.alarms]}

    def op_read_alarms(self, op):
        return [alarm_of(a) for a in self.client.read_alarms(op.get("languages"))]

    def op_disconnect(self, op):
        self.client.disconnect()
        return None

    def close(self):
        if self.stuck:
            return  # a reader thread still owns the socket; the exit closes it
        try:
            self.client.disconnect()
        except Exception:
            pass


def emit(obj):
    sys.stdout.write(json.dumps(obj) + "\n")
    sys.stdout.flush()


def batch(runner, ops):
    results = []
    for i, op in enumerate(ops):
        try:
            results.append(hexify(runner.run(op)))
        except Timeout as e:
            emit({"ok": False, "failed": i, "error": error_of(e), "results": results})
            return 1
        except Exception as e:
            emit({"ok": False, "failed": i, "error": error_of(e), "results": results})
            return 1
    emit({"ok": True, "results": results})
    return 0


def interactive(runner, first):
    failed = False
    for line in itertools.chain([first], sys.stdin):
        if not line.strip():
            continue
        try:
            emit({"ok": True, "result": hexify(runner.run(json.loads(line)))})
        except Timeout as e:
            emit({"ok": False, "error": error_of(e)})
            return 1
        except Exception as e:
            failed = True
            emit({"ok": False, "error": error_of(e)})
    return 1 if failed else 0


def main():
    first = sys.stdin.readline()
    runner = Runner()
    try:
        stripped = first.strip()
        if stripped.startswith("["):
            rest = sys.stdin.read()
            try:
                ops = json.loads(stripped + rest)
            except ValueError as e:
                emit({"ok": False, "failed": None, "error": error_of(e), "results": []})
                return 2
            return batch(runner, ops)
        return interactive(runner, first)
    finally:
        runner.close()


if __name__ == "__main__":
    code = main()
    sys.stdout.flush()
    # A notification that never came leaves a thread blocked on the socket: leave at once.
    os._exit(code)
