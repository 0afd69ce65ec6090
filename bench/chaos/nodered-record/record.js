'use strict';
// chaos-record: keeps what reaches it in a process-wide record that
// bench/chaos/nodered-worker.js reads: Catch messages (msg.error), Status
// messages (msg.status), acknowledged writes (msg.results) and read messages,
// (a write node's failure carries msg.results too: msg.error decides),
// each with the time it arrived and the PLC its source node belongs to (the
// number at the end of the node's id: conn7, read7, write7).
module.exports = function (RED) {
  const record = (global.__plcwireChaosRecord ??= { errors: [], statuses: [], acked: [], reads: [], wrong: [], expect: [] });
  const plcOf = (id) => Number(/(\d+)$/.exec(String(id))?.[1] ?? -1);
  /** A read message's statics against what the PLC holds (record.expect[plc]: [name, type, value]); counted per PLC, not kept. */
  function checkRead(plc, payload) {
    if (Date.now() >= record.from && Date.now() < record.to) record.reads[plc] = (record.reads[plc] ?? 0) + 1;
    for (const [name, type, value] of record.expect[plc] ?? []) {
      const v = payload ? payload[name] : undefined;
      if (v === undefined || v === null || typeof v === 'object') continue; // a failed tag: its error went to Catch
      // The read node shows a REAL as its shortest decimal (lib/symbols/reals.ts): the same float32.
      const same = type === 'REAL' ? Math.fround(value) === Math.fround(v) : value === v;
      if (!same && record.wrong.length < 20) record.wrong.push(`PLC ${plc} ${name}: expected ${value}, read ${JSON.stringify(v)}`);
    }
  }
  function ChaosRecord(config) {
    RED.nodes.createNode(this, config);
    this.on('input', (msg, send, done) => {
      const t = Date.now();
      if (msg.error) {
        const source = msg.error.source || {};
        record.errors.push({
          t,
          plc: plcOf(source.id),
          type: source.type,
          code: msg.error.code,
          payload: msg.payload,
          message: msg.error.message,
        });
      } else if (msg.status) {
        const source = msg.status.source || {};
        record.statuses.push({
          t,
          plc: plcOf(source.id),
          type: source.type,
          fill: msg.status.fill,
          shape: msg.status.shape,
          text: msg.status.text,
        });
      } else if (msg.results) record.acked.push({ t, plc: plcOf(msg.topic), payload: msg.payload });
      else checkRead(plcOf(msg.topic), msg.payload);
      done();
    });
  }
  RED.nodes.registerType('chaos-record', ChaosRecord);
};
