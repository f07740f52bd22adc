/**
 * The pairwise baseline's flow (SPEC §9): the pair on screen and the following one, whose
 * clips are already loading, so an answer shows the next pair at once. Answers and skips
 * are sent in order behind each other; after each the next pairs are fetched (the server's
 * queue knows what was answered). Pairs answered or skipped on this page are never shown
 * again, even when a reply races with them.
 */
import { type JudgementOut, type Label, type PairQuery, STALE } from "../api";
import { answersPair } from "../lib/annotators";
import { uuid } from "../lib/uuid";
import type { EffectContext } from "./context";

const pairKey = (p: Pick<PairQuery, "left" | "right">) => `${p.left}:${p.right}`;

export function createPairwiseFlow({ store, api, fail }: EffectContext, annotator: string) {
  const dispatch = store.dispatch;
  const get = store.getState;
  /** The pair each of this page's judgements answered (for undo). */
  const answeredPairs = new Map<number, PairQuery>();
  let queue: Promise<unknown> = Promise.resolve();

  /** Fetches the next pairs (or skips `skip` first) and fills the free slots with them. */
  async function nextPair(skip?: PairQuery): Promise<void> {
    const s = get().session;
    if (!s || s.mode !== "pairwise" || s.phase !== "ready") return;
    dispatch({ type: "pairwise", patch: { loading: true } });
    try {
      const reply = skip ? await api.skipPair(s.id, skip) : await api.pairwiseNext(s.id);
      if (reply === STALE) return;
      const pw = get().pairwise;
      const done = new Set(pw.done);
      const fresh = [reply.pair, reply.following].filter(
        (p): p is PairQuery => p !== null && !done.has(pairKey(p)),
      );
      const current = pw.current ?? fresh.shift() ?? null;
      const following = fresh.find((p) => pairKey(p) !== (current && pairKey(current))) ?? null;
      dispatch({
        type: "pairwise",
        patch: {
          current,
          following,
          loading: false,
          exhausted: reply.pair === null,
          shownAt: pw.current ? pw.shownAt : Date.now(),
          clip: reply.clip ?? null,
        },
      });
    } catch (err) {
      dispatch({ type: "pairwise", patch: { loading: false } });
      fail(err);
    }
  }

  /** Shows the following pair at once; the answer is sent in order behind the others. */
  function advancePair(): PairQuery | null {
    const pw = get().pairwise;
    const cur = pw.current;
    if (!cur) return null;
    dispatch({
      type: "pairwise",
      patch: {
        current: pw.following,
        following: null,
        done: [...pw.done, pairKey(cur)],
        shownAt: Date.now(),
      },
    });
    return cur;
  }

  function answerPair(label: Label): void {
    const st = get();
    const s = st.session;
    if (!s || s.phase !== "ready" || !st.pairwise.current) return;
    const shownAt = st.pairwise.shownAt ?? Date.now();
    const pair = advancePair()!;
    const body = {
      client_id: uuid(),
      round: s.round,
      left: [pair.left],
      right: [pair.right],
      label,
      source: "pairwise" as const,
      seconds: Math.max(0, (Date.now() - shownAt) / 1000),
      edits: 0,
      annotator,
    };
    queue = queue
      .then(async () => {
        const j = await api.submitJudgement(s.id, body);
        answeredPairs.set(j.id, pair);
        dispatch({ type: "judgement-stored", judgement: j });
        const what = label === "equal" ? "equal" : `${label} better`;
        dispatch({ type: "toast", kind: "ok", text: `Saved: ${what}.`, undo: true });
      })
      .catch((err) => {
        const pw = get().pairwise;
        dispatch({ type: "pairwise", patch: { done: pw.done.filter((k) => k !== pairKey(pair)) } });
        fail(err);
      })
      .then(() => nextPair());
  }

  function skipPair(): void {
    const s = get().session;
    if (!s || s.phase !== "ready" || !get().pairwise.current) return;
    const pair = advancePair()!;
    queue = queue.then(() => nextPair(pair));
  }

  /** A new round: nothing shown or done yet; fetch the first pairs. */
  async function start(): Promise<void> {
    dispatch({
      type: "pairwise",
      patch: { current: null, following: null, done: [], exhausted: false, shownAt: null },
    });
    await nextPair();
  }

  /** After an undo: the undone judgement's pair is asked again, now. */
  function restore(judgementId: number): void {
    const pair = answeredPairs.get(judgementId);
    if (!pair) return;
    const pw = get().pairwise;
    dispatch({
      type: "pairwise",
      patch: {
        current: pair,
        following: pw.current,
        done: pw.done.filter((k) => k !== pairKey(pair)),
        shownAt: Date.now(),
      },
    });
  }

  /**
   * Someone else answered judgement `j`: the pair on screen, or the one after it, goes when
   * it is that pair (the server no longer offers it), and the next pairs are fetched.
   * True when the pair on screen went.
   */
  function dropAnswered(j: JudgementOut): boolean {
    const pw = get().pairwise;
    const current = pw.current && answersPair(j, pw.current);
    const following = pw.following && answersPair(j, pw.following);
    if (!current && !following) return false;
    if (current) advancePair();
    else dispatch({ type: "pairwise", patch: { following: null, done: [...pw.done, pairKey(pw.following!)] } });
    queue = queue.then(() => nextPair());
    return !!current;
  }

  /** The session became shared: ask for the pairs again, which leases the first to this
   * person (the pair on screen stays). */
  function reclaim(): void {
    queue = queue.then(() => nextPair());
  }

  return { start, answer: answerPair, skip: skipPair, restore, dropAnswered, reclaim };
}

export type PairwiseFlow = ReturnType<typeof createPairwiseFlow>;
