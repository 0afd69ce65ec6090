/** The parse cache of a client: each address (or name) parsed once, to its tag or its error. */
import { PlcError, toPlcError } from '../errors';
import { addressOrSymbol } from '../symbols/resolve';
import type { DriverTag } from '../link/driver';
import type { ClientSymbols } from './symbols';

const MAX_CACHED_TAGS = 10_000;

export class TagCache<T extends DriverTag> {
  private readonly tags = new Map<string, T | PlcError>();

  /**
   * `parse` is the driver's address syntax (TagSyntax.parse); `symbols`, with
   * a symbol table, resolves what does not parse as an address.
   */
  constructor(
    private readonly parse: (address: string) => T,
    readonly symbols: ClientSymbols<T> | undefined,
  ) {}

  /**
   * The tag of an address or, with a symbol table, of a name (cached: a
   * symbol is resolved once), by addressOrSymbol. Absolute addresses come first: text that
   * parses as an address is that address (`M1`, `DB1.DBW2`, with or without
   * %), so a symbol table never changes what an address means; a symbol whose
   * name reads as an address is written quoted, as TIA writes it (`"M1"`).
   */
  get(address: string): T | PlcError {
    let tag = this.tags.get(address);
    if (tag === undefined) {
      try {
        const { tag: found, symbol } = addressOrSymbol(address, this.parse, this.symbols?.table);
        if (symbol) this.symbols?.remember(symbol);
        tag = found;
      } catch (err) {
        tag = toPlcError(err, 'INVALID_ADDRESS');
      }
      if (this.tags.size >= MAX_CACHED_TAGS) this.tags.clear();
      this.tags.set(address, tag);
    }
    return tag;
  }
}
