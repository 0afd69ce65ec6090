'use strict';
/**
 * The connection dialog's S7CommPlus endpoints (issue #25):
 *
 * POST plcwire/s7plus/certificate { url } → { ok, fingerprint, subject,
 *   validFrom, validTo } | { ok: false, code, message }: TCP, COTP with the
 *   S7CommPlus TSAPs, InitSSL, then a TLS handshake that trusts nothing and
 *   takes the PLC's certificate; the connection is closed right after it,
 *   before any S7CommPlus request (no session, nothing read or written).
 *
 * POST plcwire/s7plus/browse { url, id?, password? } → the shape the
 *   dialog's compile of sources has (lib/flows/symbol-config.ts describe():
 *   { blocks, entries, types, errors }), from the client's browse(); the
 *   password is the one typed in the dialog, else the deployed node's
 *   credential (by id). It is never part of an answer.
 */
const plc = require('../..');
const symbols = require('../../dist/lib/flows/symbol-config');
const { openTunnel } = require('../../dist/lib/s7plus/client/tunnel');
const { initSsl, peerCertificate } = require('../../dist/lib/s7plus/client/handshake');
const { startTls } = require('../../dist/lib/s7plus/transport/handshake');
const { isS7PlusEndpoint } = require('../../dist/lib/s7plus/url');

/** The longest either request may take. */
const DEADLINE_MS = 15000;

/** The s7plus:// endpoint of a request's URL; throws the parser's error or INVALID_URL for any other URL. */
function s7plusEndpoint(url) {
  const endpoint = plc.parseUrl(String(url || '').trim());
  if (!isS7PlusEndpoint(endpoint)) {
    throw new plc.PlcError('INVALID_URL', 'the PLC certificate and Browse PLC need an s7plus:// URL (S7CommPlus)');
  }
  return endpoint;
}

/** An AbortSignal that fires at the deadline or when the editor goes away; `done()` clears it. */
function requestSignal(res) {
  const stop = new AbortController();
  const timer = setTimeout(() => stop.abort(), DEADLINE_MS);
  const onClose = () => {
    if (!res.writableEnded) stop.abort();
  };
  res.on('close', onClose);
  return {
    signal: stop.signal,
    done() {
      clearTimeout(timer);
      res.off('close', onClose);
    },
  };
}

/** The PLC's certificate, trusting nothing: nothing after the TLS handshake goes on the wire. */
async function peekCertificate(endpoint, signal) {
  if (!endpoint.tls) throw new plc.PlcError('INVALID_URL', 'tls=false: the PLC is asked for plain S7CommPlus, without a certificate');
  const name = `s7plus://${endpoint.host}:${endpoint.port}`;
  const tunnel = await openTunnel(endpoint, { name, timeout: endpoint.timeout, signal });
  try {
    await initSsl(tunnel, { name, signal });
    // insecure: take any certificate, to show it; the socket is closed at once, the session never starts.
    const { socket, certificate } = await startTls(tunnel, {
      trust: { insecure: true },
      host: endpoint.host,
      timeout: endpoint.timeout,
      signal,
    });
    socket.destroy();
    return peerCertificate(certificate);
  } finally {
    tunnel.destroy();
  }
}

/**
 * The PLC's password of a dialog's request: the one typed in the dialog
 * (not Node-RED's placeholder for a stored one), else the deployed node's
 * credential (by id); undefined without either. Never part of an answer.
 */
function passwordOf(RED, body) {
  const stored = body.id ? RED.nodes.getCredentials(String(body.id)) : undefined;
  const typed = typeof body.password === 'string' && body.password !== '' && body.password !== '__PWRD__' ? body.password : undefined;
  return typed !== undefined ? typed : stored && stored.password ? stored.password : undefined;
}

function failure(err) {
  return { ok: false, code: (err && err.code) || 'PLC_ERROR', message: err && err.message ? err.message : String(err) };
}

module.exports = function s7plusAdmin(RED, canRead) {
  RED.httpAdmin.post('/plcwire/s7plus/certificate', canRead, function (req, res) {
    const body = req.body || {};
    const request = requestSignal(res);
    Promise.resolve()
      .then(() => peekCertificate(s7plusEndpoint(body.url), request.signal))
      .then((c) => ({ ok: true, fingerprint: c.fingerprint, subject: c.subject, validFrom: c.validFrom, validTo: c.validTo }), failure)
      .then((answer) => {
        request.done();
        if (!res.writableEnded) res.json(answer);
      });
  });

  RED.httpAdmin.post('/plcwire/s7plus/browse', canRead, function (req, res) {
    const body = req.body || {};
    const request = requestSignal(res);
    let client;
    Promise.resolve()
      .then(async () => {
        const endpoint = s7plusEndpoint(body.url);
        const password = passwordOf(RED, body);
        client = plc.createClient(endpoint, password !== undefined ? { password } : {});
        if (typeof client.browse !== 'function')
          throw new plc.PlcError('NOT_SUPPORTED', 'this S7CommPlus client cannot browse the PLC yet');
        await client.connect();
        const table = await client.browse({ signal: request.signal });
        return { ok: true, ...symbols.describe({ table }) };
      })
      .then((answer) => answer, failure)
      .then(async (answer) => {
        if (client) await client.close().catch(() => undefined);
        request.done();
        if (!res.writableEnded) res.json(answer);
      });
  });
};

module.exports.passwordOf = passwordOf;
