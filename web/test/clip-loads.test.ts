import { afterEach, describe, expect, it } from "vitest";
import { CLIP_REQUESTS_IN_FLIGHT, loadClips, setClipSource, unloadVideo } from "../src/views/clips";

/** The parts of a video element the clip loads touch, without a browser. */
class FakeVideo extends EventTarget {
  private attrs = new Map<string, string>();
  playbackRate = 1;
  defaultPlaybackRate = 1;
  get src(): string {
    return this.attrs.get("src") ?? "";
  }
  set src(value: string) {
    this.attrs.set("src", value);
    this.playbackRate = this.defaultPlaybackRate; // as the media element load algorithm does
  }
  hasAttribute(name: string): boolean {
    return this.attrs.has(name);
  }
  removeAttribute(name: string): void {
    this.attrs.delete(name);
  }
  pause(): void {}
  load(): void {}
}

let made: FakeVideo[] = [];
/** `n` videos given the sources /clips/c0.mp4 … and not asked for yet. */
function videos(n: number): HTMLVideoElement[] {
  return Array.from({ length: n }, (_, i) => {
    const v = new FakeVideo();
    made.push(v);
    setClipSource(v as unknown as HTMLVideoElement, `/clips/c${i}.mp4`);
    return v as unknown as HTMLVideoElement;
  });
}
const loading = (vs: HTMLVideoElement[]) => vs.filter((v) => v.hasAttribute("src")).length;

afterEach(() => {
  for (const v of made) unloadVideo(v as unknown as HTMLVideoElement);
  made = [];
});

describe("the page's clip loads", () => {
  it("asks for at most CLIP_REQUESTS_IN_FLIGHT clips at once, a group in its order", () => {
    expect(CLIP_REQUESTS_IN_FLIGHT).toBe(3);
    const group = videos(8);
    loadClips(group);
    expect(group.map((v) => v.hasAttribute("src"))).toEqual([true, true, true, false, false, false, false, false]);
  });

  it.each(["loadeddata", "canplay", "error", "abort"])("gives the slot to the next clip on %s", (type) => {
    const group = videos(4);
    loadClips(group);
    group[1]!.dispatchEvent(new Event(type));
    expect(group[3]!.src).toBe("/clips/c3.mp4");
    expect(loading(group)).toBe(4);
    // the event again (canplay after every seek of a loop) frees nothing more
    const more = videos(1);
    loadClips(more);
    group[1]!.dispatchEvent(new Event(type));
    expect(loading(more)).toBe(0);
  });

  it("lets a hover go ahead of a group's waiting clips", () => {
    const group = videos(5);
    loadClips(group);
    const [hover] = videos(1);
    loadClips([hover!]);
    group[0]!.dispatchEvent(new Event("loadeddata"));
    expect(hover!.hasAttribute("src")).toBe(true);
    expect(group[3]!.hasAttribute("src")).toBe(false);
  });

  it("frees the slot of a removed video, and never asks for one removed while waiting", () => {
    const group = videos(5);
    loadClips(group);
    unloadVideo(group[3]!); // removed while waiting
    unloadVideo(group[0]!); // removed while loading
    expect(group[0]!.hasAttribute("src")).toBe(false);
    expect(group[4]!.hasAttribute("src")).toBe(true);
    expect(group[3]!.hasAttribute("src")).toBe(false);
  });

  it("frees the slot of a video whose source is replaced, and queues the new one", () => {
    const group = videos(4);
    loadClips(group);
    setClipSource(group[0]!, "/clips/other.mp4");
    expect(group[3]!.hasAttribute("src")).toBe(true);
    expect(group[0]!.hasAttribute("src")).toBe(false);
    loadClips([group[0]!]);
    group[1]!.dispatchEvent(new Event("error"));
    expect(group[0]!.src).toBe("/clips/other.mp4");
  });

  it("keeps the speed set on a waiting clip when its source is set", () => {
    const group = videos(4);
    loadClips(group);
    group[3]!.playbackRate = 2; // startTogether set the comparison's speed meanwhile
    group[0]!.dispatchEvent(new Event("canplay"));
    expect(group[3]!.hasAttribute("src")).toBe(true);
    expect(group[3]!.playbackRate).toBe(2);
  });
});
