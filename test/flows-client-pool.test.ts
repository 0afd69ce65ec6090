/** The client pool without Node-RED or sockets: one client per PLC, the write-safety agreement, link events. */
import { expect } from 'chai';
import { EventEmitter } from 'node:events';
import type { ConnectOptions } from '../lib/connect';
import { ClientPool, withoutCredentials, type LinkStatus } from '../lib/flows/client-pool';
import type { LinkState } from '../lib/types';
import type { Endpoint } from '../lib/url';

/** A stand-in client: like a real one, its `state` is what its last 'state' event said. */
class FakeClient extends EventEmitter {
  started = 0;
  closed = 0;
  state: LinkState = 'idle';
  constructor(
    readonly endpoint: Endpoint,
    readonly options: ConnectOptions,
  ) {
    super();
  }
  start(): void {
    this.started++;
  }
  close(): Promise<void> {
    this.closed++;
    return Promise.reject(new Error('closing fails too'));
  }
  override emit(event: string | symbol, ...args: unknown[]): boolean {
    if (event === 'state') this.state = args[0] as LinkState;
    return super.emit(event, ...args);
  }
}

function pool() {
  const made: FakeClient[] = [];
  const p = new ClientPool<FakeClient>((endpoint, options) => {
    const c = new FakeClient(endpoint, options);
    made.push(c);
    return c;
  });
  return { pool: p, made };
}

const URL = 's7://10.0.0.5?rack=0&slot=1';

describe('flows: client pool', () => {
  it('owners of one PLC share one started client; the last release closes it, and always resolves', async () => {
    const { pool: p, made } = pool();
    const a = { name: 'a' };
    const b = {};
    const link = p.acquire(URL, a);
    expect(p.acquire('s7://10.0.0.5?slot=1', b)).to.equal(link);
    expect(made).to.have.length(1);
    expect(made[0]!.started).to.equal(1);
    expect(link.name).to.be.a('string').and.include('10.0.0.5');
    await p.release(link, a);
    expect(made[0]!.closed).to.equal(0);
    expect(p.size).to.equal(1);
    await p.release(link, b);
    expect(made[0]!.closed).to.equal(1);
    expect(p.size).to.equal(0);
    // Acquired again after the close: a new client.
    p.acquire(URL, a);
    expect(made).to.have.length(2);
  });

  it('another PLC gets its own client', () => {
    const { pool: p, made } = pool();
    expect(p.acquire(URL, {})).to.not.equal(p.acquire('s7://10.0.0.6?slot=1', {}));
    expect(made).to.have.length(2);
  });

  it('refuses other write-safety settings with SETTINGS_CONFLICT naming the holder and each difference; the holder keeps its link', () => {
    const { pool: p, made } = pool();
    const link = p.acquire(URL, { name: 'plant' });
    let err: (Error & { code?: string }) | undefined;
    try {
      p.acquire(`${URL}&control=true&readOnly=true`, { name: 'mine' });
    } catch (e) {
      err = e as Error & { code?: string };
    }
    expect(err?.code).to.equal('SETTINGS_CONFLICT');
    expect(err?.message).to.include(`same PLC as connection "plant" (${URL})`);
    expect(err?.message).to.include('readOnly is not set there, true here');
    expect(err?.message).to.include('control is not set there, true here');
    expect(err?.message).to.not.include('allow is');
    expect(made).to.have.length(1);
    expect(link.owners.size).to.equal(1);
    expect(p.size).to.equal(1);
  });

  it('refuses a second owner with another password (or none) with SETTINGS_CONFLICT, never showing either password', () => {
    const { pool: p, made } = pool();
    const url = 's7plus://10.0.0.5?insecure=true';
    const link = p.acquire(url, { name: 'line 1' }, { key: '', password: 'first-Secret' });
    expect(p.acquire(url, { name: 'line 2' }, { key: '', password: 'first-Secret' })).to.equal(link);
    for (const password of ['other-Secret', undefined]) {
      let err: (Error & { code?: string }) | undefined;
      try {
        p.acquire(url, { name: 'line 3' }, { key: '', ...(password !== undefined ? { password } : {}) });
      } catch (e) {
        err = e as Error & { code?: string };
      }
      expect(err?.code).to.equal('SETTINGS_CONFLICT');
      expect(err?.message).to.match(/another password|no password here/);
      expect(err?.message).to.not.include('Secret');
    }
    expect(made).to.have.length(1);
    expect(link.owners.size).to.equal(2);
  });

  it('refuses an allow-list that differs, shown as the list', () => {
    const { pool: p } = pool();
    p.acquire(`${URL}&allow=DB1,M0.0`, {});
    expect(() => p.acquire(`${URL}&allow=DB1`, {}))
      .to.throw(/allow is DB1,M0\.0 there, DB1 here/)
      .with.property('code', 'SETTINGS_CONFLICT');
  });

  it('refuses other symbol sources, saying which side has none', () => {
    const { pool: p, made } = pool();
    p.acquire(URL, {}, { key: 'k1', strict: true });
    expect(made[0]!.options).to.deep.equal({});
    expect(() => p.acquire(URL, {}, { key: '' })).to.throw(/with no symbol sources \(it has some\)/);
    expect(() => p.acquire(URL, {}, { key: 'k2' })).to.throw(/with other symbol sources/);
    const other = pool();
    other.pool.acquire(URL, {});
    expect(() => other.pool.acquire(URL, {}, { key: 'k1' }))
      .to.throw(/with symbol sources \(it has none\)/)
      .with.property('code', 'SETTINGS_CONFLICT');
  });

  it('a bad URL is INVALID_URL and opens nothing', () => {
    const { pool: p, made } = pool();
    expect(() => p.acquire('s8://x', {}))
      .to.throw()
      .with.property('code', 'INVALID_URL');
    expect(made).to.have.length(0);
    expect(p.size).to.equal(0);
  });

  it("passes the client's state, reconnects, errors and layout checks on as the link's events", () => {
    const { pool: p, made } = pool();
    const link = p.acquire(URL, {});
    const client = made[0]!;
    const statuses: LinkStatus[] = [];
    const seen: string[] = [];
    link.on('status', (s: LinkStatus) => statuses.push(s));
    link.on('link-error', (e: Error) => seen.push(`error ${e.message}`));
    link.on('layout-mismatch', (e: { db: number }) => seen.push(`mismatch ${e.db}`));
    link.on('layout-ok', () => seen.push('ok'));
    expect(link.status).to.deep.equal({ state: 'connecting' });
    client.emit('state', 'connected');
    client.emit('state', 'idle');
    client.emit('state', 'reconnecting');
    const lost = new Error('reset');
    client.emit('reconnecting', { delay: 500, error: lost });
    client.emit('error', new Error('boom'));
    client.emit('layoutMismatch', { db: 3 });
    client.emit('layoutOk', {});
    expect(statuses).to.deep.equal([{ state: 'connected' }, { state: 'reconnecting', delay: 500, error: lost }]);
    expect(link.status).to.deep.equal({ state: 'reconnecting', delay: 500, error: lost });
    expect(seen).to.deep.equal(['error boom', 'mismatch 3', 'ok']);
  });

  it('the URL without its user info', () => {
    expect(withoutCredentials('s7://user:secret@10.0.0.5?slot=1')).to.equal('s7://10.0.0.5?slot=1');
    expect(withoutCredentials(URL)).to.equal(URL);
  });
});
