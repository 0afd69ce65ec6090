#!/usr/bin/env python3
"""Runs the S7CommPlus server emulator of the s7commplus package as a peer.

s7commplus (https://github.com/gijzelaerr/s7commplus, MIT) is a Python
S7CommPlus client and S7-1200/1500 emulator written independently of plcwire.
This script is ours: it starts that emulator (its S7CommPlusServer) with the
data blocks it is given and talks to the test that started it in JSON lines.
test/support/s7commplus-peer.ts drives it.

Usage:
  server.py CONFIG_JSON

CONFIG_JSON (all keys optional):
  {"host": "127.0.0.1", "port": 0 (a free port),
   "version": 1 | 2 (the S7CommPlus protocol version it announces; 2 with TLS),
   "tls": {"cert": "cert.pem", "key": "key.pem"}    TLS after InitSSL with that
        | {"selfSigned": "DIR"}                     certificate, or with one made
                                                    here (RSA 2048) and written
                                                    into DIR; either may add
                                                    "maxVersion": "1.2" to refuse
                                                    TLS 1.3, as some PLCs do
   "maxRequestBytes": n   (it drops a connection whose request is longer, as
                           PLCSIM Advanced does past about 1 kB),
   "dbs": [{"number": 1, "size": 16,
            "variables": {"temperature": ["Real", 0], ...},
            "data": "hex of the initial bytes (from offset 0)"}]}

stdout, one JSON object a line:
  first  {"event": "listening", "host", "port", "tls", "version",
          "fingerprint": SHA-256 of the DER certificate (hex) or null,
          "cert": path of the certificate PEM or null}
  then, as they happen:
         {"event": "connected", "peer": "host:port"} and {"event": "disconnected",
          "peer"} for each client connection (disconnected once its socket is closed),
         {"event": "request", "peer", "function": the function code, "bytes": the
          frame's length from its header to its trailer, after TLS} for each request,
         {"event": "deleteObject", "peer", "session"} for each DeleteObject (a clean close),
         {"event": "write", "db", "offset", "size", "data": hex, "ok": bool}
          for each DB item a client writes (ok false: refused, nothing written),
         and one reply per command.
stdin, one JSON command a line:
  {"cmd": "cpu", "state": "RUN" | "STOP"}      -> {"event": "cpu", "state"}
  {"cmd": "read", "db", "offset", "size"}       -> {"event": "data", "db", "offset", "data": hex}
  {"cmd": "write", "db", "offset", "data": hex} -> {"event": "written", "db", "offset", "size"}
  a command that fails                          -> {"event": "error", "cmd", "message"}
When stdin closes, the server stops and the script exits 0. A bad
configuration prints {"event": "error", "message"} and exits 2.
"""

import datetime
import hashlib
import ipaddress
import json
import os
import ssl
import struct
import sys
import threading

from s7commplus import CPUState, Server
from s7commplus.protocol import ProtocolVersion

_out_lock = threading.Lock()
_client = threading.local()


def emit(obj):
    """One JSON line on stdout; the emulator's client threads and the main thread share it."""
    with _out_lock:
        sys.stdout.write(json.dumps(obj) + "\n")
        sys.stdout.flush()


class ReportingServer(Server):
    """The emulator, reporting connections, requests, DeleteObjects and DB item writes."""

    def _handle_client(self, client_sock, address):
        peer = f"{address[0]}:{address[1]}"
        _client.peer = peer  # each client has its own thread
        emit({"event": "connected", "peer": peer})
        try:
            super()._handle_client(client_sock, address)
        finally:
            emit({"event": "disconnected", "peer": peer})

    def _process_request(self, data, session_id, integrity_id_read=0, integrity_id_write=0):
        function = struct.unpack_from(">H", data, 7)[0] if len(data) >= 9 else None
        emit({"event": "request", "peer": getattr(_client, "peer", None), "function": function, "bytes": len(data)})
        return super()._process_request(data, session_id, integrity_id_read, integrity_id_write)

    def _handle_delete_object(self, seq_num, session_id):
        emit({"event": "deleteObject", "peer": getattr(_client, "peer", None), "session": session_id})
        return super()._handle_delete_object(seq_num, session_id)

    def _write_item(self, item, data):
        ok = super()._write_item(item, data)
        if item is not None:
            db, offset, size = item
            emit({"event": "write", "db": db, "offset": offset, "size": size, "data": bytes(data).hex(), "ok": ok})
        else:
            emit({"event": "write", "db": None, "offset": None, "size": None, "data": bytes(data).hex(), "ok": ok})
        return ok


def self_signed(directory):
    """A fresh RSA 2048 key and a self-signed certificate for it, written as PEM into directory.

    RSA because the TLS 1.2 suites S7 PLCs and the s7commplus client use
    (ECDHE-RSA, RSA key exchange) authenticate with an RSA key.

    It names localhost, 127.0.0.1 and ::1, so a client that checks the name
    against the certificate given as CA accepts it on the loopback.
    """
    from cryptography import x509
    from cryptography.hazmat.primitives import hashes, serialization
    from cryptography.hazmat.primitives.asymmetric import rsa
    from cryptography.x509.oid import NameOID

    key = rsa.generate_private_key(public_exponent=65537, key_size=2048)
    name = x509.Name([x509.NameAttribute(NameOID.COMMON_NAME, "s7commplus peer")])
    now = datetime.datetime.now(datetime.timezone.utc)
    cert = (
        x509.CertificateBuilder()
        .subject_name(name)
        .issuer_name(name)
        .public_key(key.public_key())
        .serial_number(x509.random_serial_number())
        .not_valid_before(now - datetime.timedelta(minutes=5))
        .not_valid_after(now + datetime.timedelta(days=1))
        .add_extension(x509.BasicConstraints(ca=True, path_length=None), critical=True)
        .add_extension(
            x509.SubjectAlternativeName(
                [
                    x509.DNSName("localhost"),
                    x509.IPAddress(ipaddress.ip_address("127.0.0.1")),
                    x509.IPAddress(ipaddress.ip_address("::1")),
                ]
            ),
            critical=False,
        )
        .sign(key, hashes.SHA256())
    )
    os.makedirs(directory, exist_ok=True)
    cert_path = os.path.join(directory, "cert.pem")
    key_path = os.path.join(directory, "key.pem")
    with open(key_path, "wb") as f:
        f.write(
            key.private_bytes(
                serialization.Encoding.PEM, serialization.PrivateFormat.PKCS8, serialization.NoEncryption()
            )
        )
    with open(cert_path, "wb") as f:
        f.write(cert.public_bytes(serialization.Encoding.PEM))
    return cert_path, key_path


def fingerprint(cert_path):
    """SHA-256 of the certificate's DER encoding, as lower-case hex."""
    with open(cert_path, "r", encoding="ascii") as f:
        der = ssl.PEM_cert_to_DER_cert(f.read())
    return hashlib.sha256(der).hexdigest()


def build(config):
    """The server, started, and what the first line reports."""
    tls = config.get("tls")
    version = config.get("version", ProtocolVersion.V2 if tls else ProtocolVersion.V1)
    options = {}
    if config.get("maxRequestBytes") is not None:
        options["max_request_bytes"] = int(config["maxRequestBytes"])
    server = ReportingServer(protocol_version=version, **options)
    for block in config.get("dbs", []):
        variables = {name: (v[0], int(v[1])) for name, v in block.get("variables", {}).items()}
        db = server.register_db(int(block["number"]), variables, size=int(block.get("size", 1024)))
        initial = bytes.fromhex(block.get("data", ""))
        if initial:
            db.write(0, initial)
    cert_path = key_path = None
    if tls:
        if "selfSigned" in tls:
            cert_path, key_path = self_signed(tls["selfSigned"])
        else:
            cert_path, key_path = tls["cert"], tls["key"]
    host = config.get("host", "127.0.0.1")
    server.start(host=host, port=int(config.get("port", 0)), use_tls=bool(tls), tls_cert=cert_path, tls_key=key_path)
    if tls and tls.get("maxVersion") == "1.2":
        # The context is made by start(); each connection wraps it after InitSSL.
        server._ssl_context.maximum_version = ssl.TLSVersion.TLSv1_2
    elif tls and tls.get("maxVersion") not in (None, "1.3"):
        raise ValueError(f"maxVersion must be 1.2 or 1.3, not {tls['maxVersion']!r}")
    port = server._server_socket.getsockname()[1]
    return server, {
        "event": "listening",
        "host": host,
        "port": port,
        "tls": bool(tls),
        "version": int(version),
        "fingerprint": fingerprint(cert_path) if cert_path else None,
        "cert": os.path.abspath(cert_path) if cert_path else None,
    }


def command(server, line):
    """Runs one stdin command and returns its reply."""
    cmd = json.loads(line)
    name = cmd.get("cmd")
    if name == "cpu":
        state = {"RUN": CPUState.RUN, "STOP": CPUState.STOP}[cmd["state"]]
        server.cpu_state = state
        return {"event": "cpu", "state": state.name}
    db = server.get_db(int(cmd["db"]))
    if db is None:
        raise KeyError(f"DB{cmd['db']} is not registered")
    if name == "read":
        data = db.read(int(cmd["offset"]), int(cmd["size"]))
        return {"event": "data", "db": db.number, "offset": int(cmd["offset"]), "data": data.hex()}
    if name == "write":
        data = bytes.fromhex(cmd["data"])
        db.write(int(cmd["offset"]), data)
        return {"event": "written", "db": db.number, "offset": int(cmd["offset"]), "size": len(data)}
    raise ValueError(f"unknown command {name!r} (cpu, read, write)")


def main():
    if len(sys.argv) != 2:
        emit({"event": "error", "message": "usage: server.py CONFIG_JSON"})
        return 2
    try:
        server, listening = build(json.loads(sys.argv[1]))
    except Exception as e:  # a bad configuration, a port in use, a certificate that does not load
        emit({"event": "error", "message": f"{type(e).__name__}: {e}"})
        return 2
    emit(listening)
    try:
        for line in sys.stdin:
            if not line.strip():
                continue
            try:
                emit(command(server, line))
            except Exception as e:
                emit({"event": "error", "cmd": line.strip(), "message": f"{type(e).__name__}: {e}"})
    finally:
        server.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
