'use strict';
/**
 * The connection dialog's S7CommPlus endpoints (issue #25); the answers are
 * the library's (lib/flows/s7plus-admin.ts):
 *
 * POST plcwire/s7plus/certificate { url } → { ok, fingerprint, subject,
 *   validFrom, validTo } | { ok: false, code, message }: the PLC's
 *   certificate taken without trusting it, closed before any session.
 *
 * POST plcwire/s7plus/browse { url, id?, password? } → { ok, blocks,
 *   entries, types, errors } (the shape of the sources' compile); the
 *   password is the one typed in the dialog, else the deployed node's
 *   credential (by id). It is never part of an answer.
 */
const { certificateAnswer, browseAnswer } = require('../../dist/lib/flows/s7plus-admin');

/** The longest either request may take. */
const DEADLINE_MS = 15000;

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

/** Answers `res` with what `ask(signal)` resolves to (it never rejects), unless the editor went away. */
function answer(res, ask) {
  const request = requestSignal(res);
  ask(request.signal).then((result) => {
    request.done();
    if (!res.writableEnded) res.json(result);
  });
}

module.exports = function s7plusAdmin(RED, canRead) {
  RED.httpAdmin.post('/plcwire/s7plus/certificate', canRead, function (req, res) {
    const body = req.body || {};
    answer(res, (signal) => certificateAnswer(String(body.url || ''), signal));
  });

  RED.httpAdmin.post('/plcwire/s7plus/browse', canRead, function (req, res) {
    const body = req.body || {};
    answer(res, (signal) => browseAnswer(String(body.url || ''), { password: passwordOf(RED, body), signal }));
  });
};

module.exports.passwordOf = passwordOf;
