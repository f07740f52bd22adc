/**
 * At most `limit` loads in flight, the rest waiting newest first: what was asked for last is
 * what the person looks at now (a hover preview, the group just filled), so it goes ahead of
 * loads asked for earlier. Pure: it never touches the DOM; `begin` starts a load and the
 * caller says when it ended (`release`). The page's clip loads use it (`views/clips.ts`).
 */

/** Where a request waits: ahead of every waiting item, or behind them (a prefetch). */
export type Place = "first" | "last";

export class LoadLimiter<T> {
  private readonly inFlight = new Set<T>();
  /** Waiting items, the next to start first. */
  private queue: T[] = [];

  /**
   * `limit`: loads in flight at most (≥ 1). `begin(item)`: starts loading `item`; called once
   * per request that gets a slot, synchronously from `request` or `release`.
   */
  constructor(
    readonly limit: number,
    private readonly begin: (item: T) => void,
  ) {
    if (!(limit >= 1)) throw new RangeError(`limit must be at least 1, got ${limit}`);
  }

  /** Items loading now. */
  get loading(): ReadonlySet<T> {
    return this.inFlight;
  }

  /** Items waiting for a slot, the next to start first. */
  get waiting(): readonly T[] {
    return this.queue;
  }

  /**
   * Asks to load `items`, in their order, as one batch: the batch waits ahead of every
   * waiting item (`"first"`, the default) or behind them (`"last"`), and as many as there
   * are free slots start at once. An item already waiting moves with its batch; one already
   * loading stays as it is.
   */
  request(items: Iterable<T>, place: Place = "first"): void {
    const batch = [...new Set(items)].filter((item) => !this.inFlight.has(item));
    if (batch.length === 0) return;
    const moved = new Set(batch);
    const rest = this.queue.filter((item) => !moved.has(item));
    this.queue = place === "first" ? [...batch, ...rest] : [...rest, ...batch];
    this.fill();
  }

  /**
   * `item`'s load ended (its data arrived, it failed or was aborted) or is no longer wanted
   * (its element was removed, its source replaced): it frees its slot, or its place in the
   * queue, and the next waiting item starts. Releasing an unknown item does nothing.
   */
  release(item: T): void {
    if (this.inFlight.delete(item)) this.fill();
    else this.queue = this.queue.filter((x) => x !== item);
  }

  private fill(): void {
    while (this.inFlight.size < this.limit && this.queue.length > 0) {
      const next = this.queue.shift()!;
      this.inFlight.add(next);
      this.begin(next);
    }
  }
}
