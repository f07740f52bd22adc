import { describe, expect, it } from "vitest";
import type { Api } from "../src/api";
import { fakeApi } from "../bench/fake-api";
import { syntheticRound } from "../bench/synthetic";
import { createController } from "../src/controller";
import { pageSettingsKey, parsePageSettings } from "../src/lib/page-settings";
import { createStore } from "../src/state";

function memoryStorage() {
  const items = new Map<string, string>();
  return {
    getItem: (k: string) => items.get(k) ?? null,
    setItem: (k: string, v: string) => void items.set(k, v),
    items,
  };
}

describe("parsePageSettings", () => {
  it("reads back what the page stored", () => {
    expect(parsePageSettings('{"speed":0.5,"target":"B"}')).toEqual({ speed: 0.5, target: "B" });
  });

  it("keeps only valid values", () => {
    expect(parsePageSettings('{"speed":3,"target":"C"}')).toEqual({});
    expect(parsePageSettings('{"speed":"1","target":"A"}')).toEqual({ target: "A" });
    expect(parsePageSettings("not json")).toEqual({});
    expect(parsePageSettings(null)).toEqual({});
    expect(parsePageSettings("[1]")).toEqual({});
  });
});

describe("page settings across a reload", () => {
  const round = syntheticRound(20, { suggestions: 5, history: 0, seed: 3 });

  async function page(storage: ReturnType<typeof memoryStorage>) {
    const store = createStore();
    const controller = createController(store, fakeApi(round, "groupwise") as Api, { storage });
    await controller.boot("s-demo");
    return store;
  }

  it("keeps the playback speed and the group clicks fill, per session", async () => {
    const storage = memoryStorage();
    const first = await page(storage);
    expect(first.getState().view.speed).toBe(1);
    first.dispatch({ type: "view", patch: { speed: 1.5 } });
    first.dispatch({ type: "target", group: "B" });
    const sid = first.getState().session!.id;
    expect(JSON.parse(storage.items.get(pageSettingsKey(sid))!)).toEqual({ speed: 1.5, target: "B" });

    const reloaded = await page(storage);
    expect(reloaded.getState().view.speed).toBe(1.5);
    expect(reloaded.getState().target).toBe("B");
  });

  it("starts from the defaults without stored settings", async () => {
    const st = (await page(memoryStorage())).getState();
    expect([st.view.speed, st.target]).toEqual([1, "A"]);
  });
});
