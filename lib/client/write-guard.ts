/** The write safety of a client: a read-only connection, and the write allow-list. */
import { alarmEntry } from '../alarms/ack-guard';
import { PlcError } from '../errors';
import type { DriverTag, TagSyntax } from '../link/driver';

export class WriteGuard<T extends DriverTag> {
  private readonly allow: readonly string[] | undefined;
  private allowed: { areas: Set<string>; tags: T[] } | undefined;

  /**
   * `syntax` gives the driver's address syntax (asked at first use: the
   * driver is a field of the client's subclass); `tag` parses an allow-list
   * address the way the client does.
   */
  constructor(
    private readonly readOnly: boolean,
    allow: readonly string[] | undefined,
    private readonly syntax: () => TagSyntax<T>,
    private readonly tag: (address: string) => T,
  ) {
    this.allow = allow && allow.length > 0 ? allow : undefined;
  }

  /** Why a write of `tag` is refused (WRITE_NOT_ALLOWED), or undefined when it may go. */
  refusal(tag: T): PlcError | undefined {
    if (this.readOnly) {
      return new PlcError('WRITE_NOT_ALLOWED', `write to "${tag.address}" refused: the connection is read-only`, { tag: tag.address });
    }
    if (!this.allow) return undefined;
    this.allowed ??= this.compile(this.allow);
    const { areas, tags } = this.allowed;
    const syntax = this.syntax();
    if (areas.has(syntax.areaOf(tag)) || tags.some((outer) => syntax.contains(outer, tag))) return undefined;
    return new PlcError(
      'WRITE_NOT_ALLOWED',
      `write to "${tag.address}" refused: not in the connection's write allow-list (${this.allow.join(', ')})`,
      { tag: tag.address },
    );
  }

  /** A bad allow-list entry is a configuration error: say so at start, not at the first write. */
  check(): void {
    if (this.allow) this.allowed ??= this.compile(this.allow);
  }

  private compile(entries: readonly string[]): { areas: Set<string>; tags: T[] } {
    const areas = new Set<string>();
    const tags: T[] = [];
    const syntax = this.syntax();
    for (const entry of entries) {
      if (alarmEntry(entry) !== undefined) continue; // ALARMS, ALARM<id>: acknowledgements (lib/alarms/ack-guard.ts), not writes
      const area = syntax.allowArea(entry.trim().toUpperCase().replace(/^%/, ''));
      if (area !== undefined) areas.add(area);
      else tags.push(this.tag(entry));
    }
    return { areas, tags };
  }
}
