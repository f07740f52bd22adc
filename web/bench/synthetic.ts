/**
 * Synthetic rounds for the benchmark and the demo page (no server): a tree shaped like the
 * server's (every leaf at depth `levels`, single-child padding where a cluster skips a
 * level), suggestion edges and judgements. Seeded, so runs are comparable.
 */
import type { Edge, JudgementOut, TreeNodeJson } from "../src/api";

/** mulberry32: a small seeded generator in [0, 1). */
export function rng(seed: number): () => number {
  let a = seed >>> 0;
  return () => {
    a = (a + 0x6d2b79f5) >>> 0;
    let t = a;
    t = Math.imul(t ^ (t >>> 15), t | 1);
    t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
    return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
  };
}

export interface SyntheticRound {
  tree: TreeNodeJson;
  levels: number;
  leaves: string[];
  medoids: Record<string, string[]>;
  suggestions: Edge[];
  judgements: JudgementOut[];
  /** Inner node ids with 2–8 leaves (group candidates). */
  candidates: Array<{ id: string; leaves: string[] }>;
}

export function syntheticRound(
  n: number,
  options: { levels?: number; suggestions?: number; history?: number; seed?: number } = {},
): SyntheticRound {
  const levels = options.levels ?? 4;
  const rand = rng(options.seed ?? 1);
  const int = (lo: number, hi: number) => lo + Math.floor(rand() * (hi - lo + 1));
  const fanout = [0, 5, 4, 4, 6]; // max children per level
  let layer: TreeNodeJson[] = Array.from({ length: n }, (_, i) => ({
    id: `b${i}`,
    kind: "leaf" as const,
    level: 0,
    size: 1,
    children: [],
    behaviour: i,
    clip: `clip${i}.mp4`,
    poster: `clip${i}.jpg`,
  }));
  let counter = 0;
  for (let level = 1; level < levels; level++) {
    const next: TreeNodeJson[] = [];
    for (let i = 0; i < layer.length; ) {
      const k = Math.min(layer.length - i, int(1, fanout[level] ?? 4));
      const children = layer.slice(i, i + k);
      const id = k === 1 ? `${children[0]!.id}@${level}` : `m${++counter}`;
      const size = children.reduce((sum, c) => sum + c.size, 0);
      next.push({ id, kind: k === 1 ? "padding" : "merge", level, size, children });
      i += k;
    }
    layer = next;
  }
  const tree: TreeNodeJson = { id: "root", kind: "merge", level: levels, size: n, children: layer };
  const leaves = Array.from({ length: n }, (_, i) => `b${i}`);
  const medoids: Record<string, string[]> = {};
  const candidates: SyntheticRound["candidates"] = [];
  const collect = (node: TreeNodeJson): string[] => {
    if (!node.children.length) return [node.id];
    const ls = node.children.flatMap(collect);
    if (node.id !== "root") medoids[node.id] = ls.slice(0, 3);
    if (!node.id.includes("@") && ls.length >= 2 && ls.length <= 8 && node.level <= 2) {
      candidates.push({ id: node.id, leaves: ls });
    }
    return ls;
  };
  collect(tree);
  const pick = () => leaves[int(0, n - 1)]!;
  const pair = (): [string, string] => {
    const a = pick();
    let b = pick();
    while (b === a) b = pick();
    return [a, b];
  };
  const k = options.suggestions ?? 100;
  const suggestions: Edge[] = Array.from({ length: k }, (_, i) => {
    const [a, b] = pair();
    return { a, b, score: 1 - i / k };
  });
  const judgements: JudgementOut[] = [];
  const history = options.history ?? 400;
  for (let id = 1; judgements.reduce((s, j) => s + j.pairs.length, 0) < history; id++) {
    const m = int(1, 4);
    const left = Array.from({ length: m }, pick);
    const right = Array.from({ length: m }, pick).filter((x) => !left.includes(x));
    if (!right.length) continue;
    const label = (["left", "right", "equal"] as const)[int(0, 2)]!;
    const value = label === "left" ? 1 : label === "right" ? 0 : 0.5;
    const count = Math.max(left.length, right.length);
    judgements.push({
      id,
      client_id: `c${id}`,
      round: 0,
      left,
      right,
      label,
      source: "explored",
      seconds: 5,
      edits: 0,
      annotator: { id: "owner", name: "owner" },
      suggestion_id: null,
      created_at: "",
      undone: false,
      pairs: Array.from({ length: count }, (_, i) => ({
        a: left[i % left.length]!,
        b: right[i % right.length]!,
        label: value,
      })),
    });
  }
  return { tree, levels, leaves, medoids, suggestions, judgements, candidates };
}
