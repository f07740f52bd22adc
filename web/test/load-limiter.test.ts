import { describe, expect, it } from "vitest";
import { LoadLimiter } from "../src/lib/load-limiter";

/** A limiter of `limit` slots that records the order loads began in. */
function limiter(limit: number) {
  const began: string[] = [];
  let most = 0;
  const l: LoadLimiter<string> = new LoadLimiter<string>(limit, (item) => {
    began.push(item);
    most = Math.max(most, l.loading.size);
  });
  return { l, began, most: () => most };
}

describe("the clip-load limiter", () => {
  it("starts up to its limit at once and queues the rest", () => {
    const { l, began } = limiter(3);
    l.request(["a1", "a2", "a3", "a4", "a5"]);
    expect(began).toEqual(["a1", "a2", "a3"]);
    expect([...l.loading]).toEqual(["a1", "a2", "a3"]);
    expect(l.waiting).toEqual(["a4", "a5"]);
  });

  it("starts the newest request first, a batch in its own order", () => {
    const { l, began } = limiter(1);
    l.request(["a1", "a2", "a3"]); // a group of clips
    l.request(["hover"]); // then the pointer rests on a leaf
    expect(l.waiting).toEqual(["hover", "a2", "a3"]);
    l.request(["b1", "b2"]); // then another group
    expect(l.waiting).toEqual(["b1", "b2", "hover", "a2", "a3"]);
    for (const item of ["a1", "b1", "b2", "hover", "a2"]) l.release(item);
    expect(began).toEqual(["a1", "b1", "b2", "hover", "a2", "a3"]);
  });

  it("puts a prefetch behind everything waiting, and a waiting item asked for again ahead", () => {
    const { l } = limiter(1);
    l.request(["now"]);
    l.request(["next1", "next2"], "last");
    l.request(["a1"]);
    expect(l.waiting).toEqual(["a1", "next1", "next2"]);
    l.request(["next2"]); // the prefetched pair is shown now
    expect(l.waiting).toEqual(["next2", "a1", "next1"]);
    l.request(["now"]); // loading already: stays as it is, not queued twice
    expect([...l.loading]).toEqual(["now"]);
    expect(l.waiting).toEqual(["next2", "a1", "next1"]);
  });

  it("frees a slot when a load ends", () => {
    const { l, began } = limiter(2);
    l.request(["a", "b", "c"]);
    l.release("b");
    expect(began).toEqual(["a", "b", "c"]);
    expect([...l.loading]).toEqual(["a", "c"]);
    expect(l.waiting).toEqual([]);
  });

  it("frees the slot of a video removed while loading, and forgets one removed while waiting", () => {
    const { l, began } = limiter(1);
    l.request(["a", "b", "c"]);
    l.release("b"); // removed before its turn: never starts
    expect(l.waiting).toEqual(["c"]);
    l.release("a"); // removed while loading: the next one starts
    expect(began).toEqual(["a", "c"]);
    l.release("a"); // again, or an item it never saw: nothing happens
    l.release("zzz");
    expect([...l.loading]).toEqual(["c"]);
  });

  it("never has more than its limit in flight", () => {
    const { l, most } = limiter(3);
    // 16 clips of two groups, hovers, removals and ends interleaved
    l.request(Array.from({ length: 8 }, (_, i) => `a${i}`));
    l.request(Array.from({ length: 8 }, (_, i) => `b${i}`));
    for (let i = 0; i < 40; i++) {
      if (i % 3 === 0) l.request([`hover${i}`]);
      if (i % 4 === 1) l.request([`pre${i}`], "last");
      const done = [...l.loading][i % Math.max(1, l.loading.size)];
      if (done !== undefined) l.release(done);
      if (i % 5 === 2 && l.waiting.length) l.release(l.waiting[l.waiting.length - 1]!);
      expect(l.loading.size).toBeLessThanOrEqual(3);
    }
    expect(most()).toBe(3);
    while (l.loading.size) l.release([...l.loading][0]!);
    expect(l.waiting).toEqual([]);
  });

  it("copes with a load that ends as soon as it begins", () => {
    const began: string[] = [];
    const l: LoadLimiter<string> = new LoadLimiter<string>(2, (item) => {
      began.push(item);
      if (item.startsWith("cached")) l.release(item); // e.g. no source: released at once
    });
    l.request(["cached1", "cached2", "a", "b", "c"]);
    expect(began).toEqual(["cached1", "cached2", "a", "b"]);
    expect([...l.loading]).toEqual(["a", "b"]);
    expect(l.waiting).toEqual(["c"]);
  });

  it("needs a limit of at least one", () => {
    expect(() => new LoadLimiter(0, () => undefined)).toThrow(RangeError);
  });
});
