import type { TreeJson } from "../src/lib/tree";

const leaf = (i: number): TreeJson => ({ id: `b${i}`, level: 0, children: [], behaviour: i, clip: `c${i}.mp4` });

/**
 * The 4-leaf tree of the tests:            root (level 2)
 *                                        /              \
 *                               m1 (level 1)          m2 (level 1)
 *                               /        \            /        \
 *                              b0        b1          b2        b3
 */
export const FOUR: TreeJson = {
  id: "root",
  level: 2,
  children: [
    { id: "m1", level: 1, children: [leaf(0), leaf(1)] },
    { id: "m2", level: 1, children: [leaf(2), leaf(3)] },
  ],
};

/** Child order, not id order, decides the leaf order: b2 comes first. Padding above b4. */
export const PADDED: TreeJson = {
  id: "root",
  level: 3,
  children: [
    {
      id: "m5",
      level: 2,
      children: [
        { id: "m6", level: 1, children: [leaf(2), leaf(0), leaf(1)] },
        { id: "b4@1", level: 1, children: [leaf(4)] },
      ],
    },
    { id: "b3@2", level: 2, children: [{ id: "b3@1", level: 1, children: [leaf(3)] }] },
  ],
};
