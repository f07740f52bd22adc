/**
 * Stale-response dropping: one sequence number per resource.
 *
 * Every request for a resource takes a ticket; a response is current only while its ticket is
 * the newest for that resource. A newer request, or `invalidate` (the state moved on by
 * another route, e.g. an SSE `state` event), makes older responses stale, and the caller
 * ignores them instead of overwriting newer state with older data.
 */
export class Latest {
  private readonly seq = new Map<string, number>();

  /** A ticket for a new request of `resource`; older tickets become stale. */
  take(resource: string): number {
    const next = (this.seq.get(resource) ?? 0) + 1;
    this.seq.set(resource, next);
    return next;
  }

  /** Whether a response to the request holding `ticket` may still be applied. */
  isCurrent(resource: string, ticket: number): boolean {
    return this.seq.get(resource) === ticket;
  }

  /** Marks every request of `resource` in flight as stale. */
  invalidate(resource: string): void {
    this.take(resource);
  }
}
