/**
 * Helpers of the S7CommPlus transport tests (test/s7plus-tls*.test.ts):
 * a COTP-connected socket pair on 127.0.0.1, one frame read with a deadline,
 * and the s7commplus package's (MIT) server emulator started as a child.
 */
import { spawn, spawnSync, type ChildProcess } from 'node:child_process';
import * as fs from 'node:fs';
import * as net from 'node:net';
import * as path from 'node:path';
import { FrameReader } from '../../lib/link/framer';
import { checkTpkt } from '../../lib/s7/codec/tpkt';
import { decodeCotp, encodeConnectionConfirm } from '../../lib/s7/codec/cotp';

/** Reads one whole TPKT frame; resolves it with the bytes that came after it. Rejects on close or after `ms`. */
export function readFrame(socket: net.Socket, ms = 5000): Promise<{ frame: Buffer; rest: Buffer }> {
  return new Promise((resolve, reject) => {
    const reader = new FrameReader(checkTpkt);
    let all = Buffer.alloc(0);
    const timer = setTimeout(() => done(new Error(`no TPKT frame within ${ms} ms`)), ms);
    const onData = (chunk: Buffer) => {
      all = Buffer.concat([all, chunk]);
      let frames: Buffer[];
      try {
        frames = reader.push(chunk);
      } catch (err) {
        return done(err as Error);
      }
      if (frames.length > 0) done(undefined, { frame: frames[0]!, rest: all.subarray(frames[0]!.length) });
    };
    const onClose = () => done(new Error('closed before a whole TPKT frame'));
    function done(err: Error | undefined, value?: { frame: Buffer; rest: Buffer }) {
      clearTimeout(timer);
      socket.removeListener('data', onData);
      socket.removeListener('close', onClose);
      socket.pause();
      if (err) reject(err);
      else resolve(value!);
    }
    socket.on('data', onData);
    socket.once('close', onClose);
    socket.resume();
  });
}

/**
 * A COTP connection request as an S7CommPlus client sends it: calling TSAP
 * 0x0600, called TSAP the string "SIMATIC-ROOT-HMI", TPDU size code 0x0A
 * (the s7commplus package (MIT), protocol.py S7COMMPLUS_LOCAL_TSAP /
 * S7COMMPLUS_REMOTE_TSAP, transport.py _build_cotp_cr).
 */
export function s7plusConnectionRequest(sourceRef = 0x0001): Buffer {
  const tsap = Buffer.from('SIMATIC-ROOT-HMI', 'ascii');
  const params = Buffer.concat([Buffer.from([0xc1, 2, 0x06, 0x00, 0xc2, tsap.length]), tsap, Buffer.from([0xc0, 1, 0x0a])]);
  const cotp = Buffer.concat([Buffer.from([6 + params.length, 0xe0, 0, 0, sourceRef >> 8, sourceRef & 0xff, 0]), params]);
  const frame = Buffer.alloc(4 + cotp.length);
  frame.writeUInt8(3, 0);
  frame.writeUInt16BE(frame.length, 2);
  cotp.copy(frame, 4);
  return frame;
}

/** Client side of the COTP connect: sends the CR, awaits the CC; returns the bytes after it and the TPDU size. */
export async function cotpConnect(socket: net.Socket, ms = 5000): Promise<{ head: Buffer; tpduSize: number }> {
  socket.write(s7plusConnectionRequest());
  const { frame, rest } = await readFrame(socket, ms);
  const cc = decodeCotp(frame);
  if (cc.type !== 'CC') throw new Error(`expected a COTP CC, got ${cc.type}`);
  return { head: rest, tpduSize: cc.tpduSize > 0 ? 1 << cc.tpduSize : 128 };
}

/** Server side: awaits a CR, answers a CC with `tpduCode`; returns the bytes after the CR. */
export async function cotpAccept(socket: net.Socket, tpduCode = 0x0a, ms = 5000): Promise<Buffer> {
  const { frame, rest } = await readFrame(socket, ms);
  const cr = decodeCotp(frame);
  if (cr.type !== 'CR') throw new Error(`expected a COTP CR, got ${cr.type}`);
  socket.write(
    encodeConnectionConfirm({
      sourceRef: 0x0042,
      destinationRef: cr.sourceRef,
      callingTsap: 0x0600,
      calledTsap: 0x0100,
      tpduSize: tpduCode,
    }),
  );
  return rest;
}

/** A TCP server on 127.0.0.1 that counts its open connections. */
export async function countingServer(
  onSocket: (s: net.Socket) => void,
): Promise<{ server: net.Server; port: number; open: () => Promise<number> }> {
  const server = net.createServer(onSocket);
  await new Promise<void>((r) => server.listen(0, '127.0.0.1', r));
  const port = (server.address() as net.AddressInfo).port;
  const open = () => new Promise<number>((resolve, reject) => server.getConnections((err, n) => (err ? reject(err) : resolve(n))));
  return { server, port, open };
}

/**
 * The Python interpreter that has the s7commplus package, or a reason why
 * there is none: PLCWIRE_S7COMMPLUS_PYTHON, else the venv the peer installer
 * makes (test/interop/.venv-s7commplus).
 */
export function s7commplusPython(): { python?: string; reason?: string } {
  const root = path.resolve(__dirname, '../../..');
  const candidates = [process.env.PLCWIRE_S7COMMPLUS_PYTHON, path.join(root, 'test/interop/.venv-s7commplus/bin/python')].filter(
    (p): p is string => !!p && fs.existsSync(p),
  );
  for (const python of candidates) {
    if (spawnSync(python, ['-c', 'import s7commplus.server'], { stdio: 'ignore' }).status === 0) return { python };
  }
  return { reason: 'the s7commplus Python package is not installed (test/interop/.venv-s7commplus, or PLCWIRE_S7COMMPLUS_PYTHON)' };
}

// Starts the emulator on a free port with TLS (V2) or without (V1); prints {"port": n}; stops when stdin closes.
const SERVER_SCRIPT = `
import json, sys
from s7commplus.server import S7CommPlusServer
from s7commplus.protocol import ProtocolVersion
cert, key = sys.argv[1], sys.argv[2]
tls = cert != '-'
server = S7CommPlusServer(protocol_version=ProtocolVersion.V2 if tls else ProtocolVersion.V1)
server.register_db(1, {"x": ("Int", 0)}, size=16)
server.start(host="127.0.0.1", port=0, use_tls=tls, tls_cert=cert if tls else None, tls_key=key if tls else None)
print(json.dumps({"port": server._server_socket.getsockname()[1]}), flush=True)
sys.stdin.read()
server.stop()
`;

/** Starts the s7commplus server emulator; resolves its port once it listens. */
export async function startPythonServer(
  python: string,
  cert: string | undefined,
  key: string | undefined,
  ms = 20000,
): Promise<{ port: number; child: ChildProcess; stop: () => Promise<void> }> {
  const child = spawn(python, ['-c', SERVER_SCRIPT, cert ?? '-', key ?? '-'], { stdio: ['pipe', 'pipe', 'pipe'] });
  let stderr = '';
  child.stderr!.on('data', (d) => (stderr += d));
  const exited = new Promise<void>((r) => child.once('exit', () => r()));
  const port = await new Promise<number>((resolve, reject) => {
    let out = '';
    const timer = setTimeout(() => fail(new Error(`the s7commplus server did not start within ${ms} ms: ${stderr}`)), ms);
    const onData = (d: Buffer) => {
      out += d.toString();
      const line = out.split('\n')[0];
      if (out.includes('\n')) {
        clearTimeout(timer);
        child.stdout!.removeListener('data', onData);
        resolve((JSON.parse(line!) as { port: number }).port);
      }
    };
    function fail(err: Error) {
      child.kill();
      reject(err);
    }
    child.stdout!.on('data', onData);
    child.once('exit', (code) => fail(new Error(`the s7commplus server exited (${code}): ${stderr}`)));
  });
  const stop = async () => {
    child.stdin!.end();
    const timer = setTimeout(() => child.kill(), 10000);
    await exited;
    clearTimeout(timer);
  };
  return { port, child, stop };
}
