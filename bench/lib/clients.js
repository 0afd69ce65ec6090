'use strict';
// The three S7 clients behind one shape, each through its documented API:
//   open({ port, pdu, addresses }) → { read(): Promise<Record<address, value>>, close() }
// and our S7CommPlus client ('ours-s7plus': open({ port, fingerprint, maxItems, addresses }),
// with requests() counting the requests it sent).
// LOADERS[name]() requires the library, so a worker can load code before it
// takes its memory baseline (memory per tag then counts tags, not code).
const { once } = require('node:events');
const path = require('node:path');
const { peer, plcwire, DIST } = require('./peers');

const CLIENTS = {
  async ours({ port, pdu, addresses }) {
    const { connect } = plcwire();
    const plc = await connect(`s7://127.0.0.1:${port}?rack=0&slot=1&pdu=${pdu}&timeout=10000`);
    plc.on('error', () => undefined);
    return { read: () => plc.read(addresses), close: () => plc.close() };
  },

  async 'ours-s7plus'({ port, fingerprint, maxItems, addresses }) {
    const { connect } = plcwire();
    const limit = maxItems ? `&maxItems=${maxItems}` : '';
    const plc = await connect(`s7plus://127.0.0.1:${port}?fingerprint=${fingerprint}&timeout=10000${limit}`);
    plc.on('error', () => undefined);
    return {
      read: () => plc.read(addresses),
      close: () => plc.close(),
      requests: () => plc.stats.requestsSent,
      itemLimit: () => plc.maxItems,
    };
  },

  /**
   * Our S7CommPlus transport alone, the floor under 'ours-s7plus': the same session (TLS in the COTP
   * tunnel, sequence numbers, integrity ids, one request in flight) sends the same GetMultiVariables
   * requests by LID, built from the browse once, and leaves the answers undecoded. The first read() is
   * a real one (checked by the worker); the others are the floor's.
   */
  async 'ours-s7plus-transport'({ port, fingerprint, maxItems, addresses }) {
    const { connect } = plcwire();
    const { readAsk } = require(path.join(DIST, 'lib/s7plus/client/asks.js'));
    const { cut } = require(path.join(DIST, 'lib/s7plus/client/chunks.js'));
    const { addressBytes } = require(path.join(DIST, 'lib/s7plus/codec/variables.js'));
    const { Ids } = require(path.join(DIST, 'lib/s7plus/constants.js'));
    const limit = maxItems ? `&maxItems=${maxItems}` : '';
    const plc = await connect(`s7plus://127.0.0.1:${port}?fingerprint=${fingerprint}&timeout=10000${limit}`);
    plc.on('error', () => undefined);
    const table = await plc.browse();
    // The items ours sends: each name's LIDs and SymbolCrc.
    const items = addresses.map((a) => {
      const { area, lids, symbolCrc } = table.lookup(a).access;
      return { symbolCrc: symbolCrc ?? 0, accessArea: area, accessSubArea: Ids.DBValueActual, lids: [...lids] };
    });
    // Cut as ours cuts them (after the first read: the PLC's SystemLimits, frames of at most the TPDU, 1024 bytes).
    let chunks;
    const raw = async () => {
      chunks ??= cut(items, { maxItems: () => plc.maxItems, refused: () => undefined, maxFrame: () => 1024 }, addressBytes);
      // The client's live session (BaseClient's `session`): what its reads go through; the answer is not decoded.
      const session = plc.session;
      for (const chunk of chunks) await session.request({ ...readAsk(chunk), decode: () => ({ body: undefined }) });
    };
    let first = true;
    return {
      read: () => (first ? ((first = false), plc.read(addresses)) : raw()),
      close: () => plc.close(),
      requests: () => plc.stats.requestsSent,
    };
  },

  async nodes7({ port, pdu, addresses }) {
    const NodeS7 = peer('nodes7');
    const conn = new NodeS7({ silent: true });
    conn.requestMaxPDU = pdu; // nodes7 asks for 960 unless told; the field is read at connect
    await new Promise((resolve, reject) =>
      conn.initiateConnection({ host: '127.0.0.1', port, rack: 0, slot: 1, timeout: 10000 }, (err) =>
        err ? reject(new Error(`nodes7 connect: ${JSON.stringify(err)}`)) : resolve(),
      ),
    );
    conn.setTranslationCB((tag) => tag);
    conn.addItems(addresses.slice());
    return {
      read: () =>
        new Promise((resolve, reject) =>
          conn.readAllItems((bad, values) => (bad ? reject(new Error('nodes7: bad quality')) : resolve(values))),
        ),
      close: () => new Promise((resolve) => conn.dropConnection(() => resolve())),
    };
  },

  async 'st-one'({ port, pdu, addresses }) {
    const { S7Endpoint, S7ItemGroup } = peer('@st-one-io/nodes7');
    const plc = new S7Endpoint({
      host: '127.0.0.1',
      port,
      rack: 0,
      slot: 1,
      autoReconnect: 0,
      s7ConnOpts: { maxPDUSize: pdu, timeout: 10000 },
    });
    plc.on('error', () => undefined);
    const connected = once(plc, 'connect');
    await plc.connect();
    await connected;
    const group = new S7ItemGroup(plc);
    group.addItems(addresses.slice());
    return { read: () => group.readAllItems(), close: () => plc.disconnect() };
  },
};

const LOADERS = {
  ours: () => plcwire(),
  'ours-s7plus': () => plcwire(),
  'ours-s7plus-transport': () => plcwire(),
  nodes7: () => peer('nodes7'),
  'st-one': () => peer('@st-one-io/nodes7'),
};

/** The S7 clients the comparison tables put side by side. */
const CLIENT_NAMES = ['ours', 'nodes7', 'st-one'];

module.exports = { CLIENTS, LOADERS, CLIENT_NAMES };
