import { describe, expect, it } from "vitest";
import type { Annotator, JudgementOut } from "../src/api";
import {
  EMPTY_BOARD,
  OWNER_COLOUR,
  afterAnswerElsewhere,
  agreementText,
  agreementTitle,
  annotatorColours,
  answersPair,
  historyRows,
  initials,
  isShared,
  judgementAnnotator,
  kappaText,
  modelAgreementText,
  undoTarget,
  withJudgementEvent,
  withSessionState,
} from "../src/lib/annotators";

const ann = { id: "a-1", name: "Ann" };
const owner = { id: "owner", name: "owner" };

function person(id: string, name: string, comparisons = 0, pairs = 0): Annotator {
  return {
    id,
    name,
    comparisons,
    pairs,
    shown_s: 30,
    agreement: { kappa: null, share: null, n: 0 },
    model_agreement: { share: null, n: 0 },
  };
}

let nextId = 1;
function judgement(who: { id: string; name: string }, patch: Partial<JudgementOut> = {}): JudgementOut {
  return {
    id: nextId++,
    client_id: "c",
    round: 0,
    left: ["b1", "b2"],
    right: ["b3"],
    label: "left",
    source: "suggested",
    seconds: 4,
    edits: 0,
    annotator: who as unknown as JudgementOut["annotator"],
    created_at: "2030-01-01T00:00:00Z",
    undone: false,
    pairs: [
      { a: "b1", b: "b3", label: 1 },
      { a: "b2", b: "b3", label: 1 },
    ],
    ...patch,
  };
}

describe("who made a judgement", () => {
  it("reads the server's {id, name}, and calls a judgement from before shared sessions the owner's", () => {
    expect(judgementAnnotator(judgement(ann))).toEqual(ann);
    expect(judgementAnnotator({ annotator: "" as unknown as JudgementOut["annotator"] })).toEqual(owner);
    expect(judgementAnnotator({ annotator: "Kim" as unknown as JudgementOut["annotator"] })).toEqual({ id: "owner", name: "Kim" });
  });

  it("a session is shared once someone besides the owner is in it, or this page is not the owner", () => {
    expect(isShared({ me: { ...owner, owner: true }, annotators: [person("owner", "owner")] })).toBe(false);
    expect(isShared({ me: { ...owner, owner: true }, annotators: [person("owner", "owner"), person("a-1", "Ann")] })).toBe(true);
    expect(isShared({ me: { ...ann, owner: false }, annotators: [] })).toBe(true);
    expect(isShared({})).toBe(false); // a server without shared sessions
  });
});

describe("initials and colours", () => {
  it("takes the first letters of the first and last word", () => {
    expect(initials("Ada Lovelace")).toBe("AL");
    expect(initials("ada king lovelace")).toBe("AL");
    expect(initials("bob")).toBe("B");
    expect(initials("  jean-luc ")).toBe("JL");
    expect(initials("émile")).toBe("É");
    expect(initials("🦊 fox")).toBe("🦊F");
    expect(initials("   ")).toBe("?");
  });

  it("gives the owner their colour and the others theirs in list order, stable across pages", () => {
    const a = annotatorColours(["owner", "a-1", "a-2", "a-1"]);
    const b = annotatorColours(["owner", "a-1", "a-2"]);
    expect(a.get("owner")).toBe(OWNER_COLOUR);
    expect(a.get("a-1")).not.toBe(a.get("a-2"));
    expect([...a]).toEqual([...b]);
    expect(a.size).toBe(3);
  });
});

describe("live counters", () => {
  const base = withSessionState(EMPTY_BOARD, [person("owner", "owner", 2, 5), person("a-1", "Ann", 1, 2)], 10);

  it("adds a judgement event to its person: one comparison and its pairs", () => {
    const after = withJudgementEvent(base, judgement(ann), 11);
    expect(after.list.map((p) => [p.id, p.comparisons, p.pairs])).toEqual([
      ["owner", 2, 5],
      ["a-1", 2, 4],
    ]);
    expect(after.rev).toBe(11);
    expect(after.list[1]!.shown_s).toBe(30); // time shown comes with the next state
  });

  it("does not count an event the last state already holds, nor take an older state", () => {
    expect(withJudgementEvent(base, judgement(ann), 10)).toBe(base);
    expect(withJudgementEvent(base, judgement(ann), 9)).toBe(base);
    const newer = withJudgementEvent(base, judgement(ann), 12);
    expect(withSessionState(newer, [person("owner", "owner")], 11)).toBe(newer);
    // a state at the event's revision or later counts it itself
    const state = [person("owner", "owner", 2, 5), person("a-1", "Ann", 2, 4)];
    expect(withSessionState(newer, state, 12).list).toEqual(state);
  });

  it("takes off an undone judgement with the pairs it had", () => {
    const stored = judgement(owner);
    const one = withJudgementEvent(base, stored, 11);
    const undone = { ...stored, undone: true, pairs: [] };
    const two = withJudgementEvent(one, undone, 12, stored);
    expect(two.list[0]).toMatchObject({ comparisons: 2, pairs: 5 });
    // without the stored judgement the counters wait for the next state
    expect(withJudgementEvent(one, undone, 12).list).toBe(one.list);
  });

  it("adds a person the board did not know yet, and never counts below zero", () => {
    const bob = { id: "a-2", name: "Bob" };
    const after = withJudgementEvent(EMPTY_BOARD, judgement(bob), 3);
    expect(after.list).toEqual([{ ...person("a-2", "Bob", 1, 2), shown_s: 0 }]);
    const j = judgement(bob, { pairs: [{ a: "b1", b: "b3", label: 1 }] });
    const low = withJudgementEvent(EMPTY_BOARD, { ...j, undone: true, pairs: [] }, 4, { ...j, pairs: [...j.pairs, ...j.pairs, ...j.pairs] });
    expect(low.list[0]).toMatchObject({ comparisons: 0, pairs: 0 });
  });

  it("a state read by GET (no revision) replaces the counters and keeps the revision", () => {
    const got = withSessionState(base, [person("owner", "owner", 7, 9)], null);
    expect(got.rev).toBe(10);
    expect(got.list[0]!.comparisons).toBe(7);
    expect(withSessionState(base, undefined, 20)).toBe(base); // a server without the list
  });
});

describe("agreement in words", () => {
  it("gives κ and the share with the n they rest on", () => {
    expect(agreementText({ kappa: 0.6234, share: 0.8, n: 10 })).toBe("κ 0.62 · 80 % of 10");
    expect(agreementText({ kappa: -0.1, share: 0.45, n: 20 })).toBe("κ −0.10 · 45 % of 20");
    expect(agreementText({ kappa: null, share: 1, n: 3 })).toBe("κ – · 100 % of 3");
    expect(agreementText({ kappa: null, share: null, n: 0 })).toBe("no overlap yet");
    expect(kappaText(Number.NaN)).toBe("–");
  });

  it("says the reward model's agreement, or a dash before there is any", () => {
    // its unit named: not the "Pairs" column's training pairs (issue 40)
    expect(modelAgreementText({ share: 0.75, n: 8 })).toBe("75 % of 8 compared pairs");
    expect(modelAgreementText({ share: null, n: 0 })).toBe("–");
  });

  it("writes the whole sentence for a title", () => {
    const p = { ...person("a-1", "Ann"), agreement: { kappa: 0.5, share: 0.75, n: 4 }, model_agreement: { share: 0.5, n: 6 } };
    expect(agreementTitle(p)).toBe(
      "Ann agrees with the others on 75 % of 4 behaviour pairs both judged (Cohen's κ 0.50); " +
        "the reward model prefers the same behaviour in 50 % of the 6 behaviour pairs they compared " +
        "(each left behaviour with each right one).",
    );
    expect(agreementTitle(person("owner", "owner"))).toMatch(/judged no behaviour pair someone else judged too; the reward model has not/);
  });
});

describe("the history list", () => {
  it("lists the round's judgements newest first, each with its person", () => {
    const colours = annotatorColours(["owner", "a-1"]);
    const a = judgement(owner, { label: "equal" });
    const b = judgement(ann, { left: ["b9"], right: ["b4"], label: "right", pairs: [{ a: "b9", b: "b4", label: 0 }] });
    const rows = historyRows([a, b], colours, "a-1", "groupwise");
    expect(rows.map((r) => [r.initials, r.mine, r.text])).toEqual([
      ["A", true, "B better · b9 vs b4"],
      ["O", false, "equal · 2 vs b3"],
    ]);
    expect(rows[0]!.colour).toBe(colours.get("a-1"));
    expect(rows[0]!.title).toBe("Ann (you): b9 vs b4 · B better · 1 pair · 4 s");
    expect(historyRows([b], colours, "owner", "pairwise")[0]!.text).toBe("right better · b9 vs b4");
  });
});

describe("answers elsewhere", () => {
  const sug = { id: 7, left: ["b1", "b2"], right: ["b3"] };
  const groups = { A: ["b2", "b1"], B: ["b3"] };
  const origin = { source: "suggested", edits: 0, suggestion: sug };

  it("replaces the suggestion on screen when someone else answered it, untouched", () => {
    expect(afterAnswerElsewhere(groups, origin, judgement(ann, { suggestion_id: 7 }), "owner")).toBe("replace");
    // edited, or the groups moved on: the person's own work stays
    expect(afterAnswerElsewhere(groups, { ...origin, edits: 1 }, judgement(ann, { suggestion_id: 7 }), "owner")).toBe("keep");
    expect(afterAnswerElsewhere(groups, origin, judgement(ann, { suggestion_id: 8 }), "owner")).toBeNull();
    expect(afterAnswerElsewhere(groups, { ...origin, source: "explored" }, judgement(ann, { suggestion_id: 7 }), "owner")).toBeNull();
  });

  it("ignores this page's own answers and undone ones", () => {
    expect(afterAnswerElsewhere(groups, origin, judgement(ann, { suggestion_id: 7 }), "a-1")).toBeNull();
    expect(afterAnswerElsewhere(groups, origin, judgement(ann, { suggestion_id: 7, undone: true }), "owner")).toBeNull();
  });

  it("matches by the groups, either side, when no suggestion id is known", () => {
    const noId = { ...origin, suggestion: { left: sug.left, right: sug.right } };
    expect(afterAnswerElsewhere(groups, noId, judgement(ann, { left: ["b3"], right: ["b1", "b2"] }), "owner")).toBe("replace");
    expect(afterAnswerElsewhere(groups, noId, judgement(ann, { left: ["b3"], right: ["b1"] }), "owner")).toBeNull();
  });

  it("knows a pair answered in either order", () => {
    const p = { left: "b4", right: "b9" };
    expect(answersPair({ left: ["b9"], right: ["b4"] }, p)).toBe(true);
    expect(answersPair({ left: ["b4"], right: ["b9"] }, p)).toBe(true);
    expect(answersPair({ left: ["b4", "b1"], right: ["b9"] }, p)).toBe(false);
    expect(answersPair({ left: ["b4"], right: ["b8"] }, p)).toBe(false);
  });
});

describe("undo", () => {
  it("takes back this person's last judgement of the round, else the round's last", () => {
    const a = judgement(ann);
    const o = judgement(owner);
    expect(undoTarget([a, o], "a-1")).toBe(a);
    expect(undoTarget([a, o], "owner")).toBe(o);
    expect(undoTarget([o], "a-1")).toBe(o); // the server refuses it, and says why
    expect(undoTarget([], "owner")).toBeNull();
  });
});
