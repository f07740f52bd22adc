/**
 * The legend of the exploration view, which is also where the edge layers are switched:
 * suggested comparisons (toggle, how many: k), given comparisons (toggle), bundling
 * strength, and the meaning of group tints and of the "not compared yet" marks.
 */
import type { ViewSettings } from "../state";
import { h, text } from "./dom";
import type { HistoryEdge } from "./edge-canvas";

export interface Legend {
  element: HTMLElement;
  update(view: ViewSettings, maxK: number, suggestions: number, history: readonly HistoryEdge[]): void;
}

export function createLegend(onChange: (patch: Partial<ViewSettings>) => void): Legend {
  const showSuggestions = h("input", { type: "checkbox", checked: true });
  const k = h("input", { type: "range", min: 0, max: 100, step: 1, "aria-label": "Number of suggested comparisons shown" });
  const kOut = h("output", { class: "num" });
  const showHistory = h("input", { type: "checkbox", checked: true });
  const beta = h("input", { type: "range", min: 0, max: 1, step: 0.05, "aria-label": "Edge bundling strength" });
  const historyCount = h("span", { class: "count" });
  const suggestionCount = h("span", { class: "count" });
  const swatch = (cls: string) => h("span", { class: `swatch ${cls}`, "aria-hidden": "true" });
  const element = h(
    "footer",
    { class: "legend", "aria-label": "Legend and edge layers" },
    h(
      "div",
      { class: "legend-row" },
      h("label", { class: "legend-item toggle" }, showSuggestions, swatch("line suggestion"), "Suggested comparisons ", suggestionCount),
      h("label", { class: "legend-item slider" }, "show", k, kOut),
    ),
    h(
      "div",
      { class: "legend-row" },
      h("label", { class: "legend-item toggle" }, showHistory, swatch("line history"), "Given: preferred → other ", historyCount),
      h("span", { class: "legend-item" }, swatch("line equal"), "equal"),
      h("label", { class: "legend-item slider" }, "bundling", beta),
    ),
    h(
      "div",
      { class: "legend-row" },
      h("span", { class: "legend-item" }, swatch("fill group-A"), "group A"),
      h("span", { class: "legend-item" }, swatch("fill group-B"), "group B (hatched)"),
      h("span", { class: "legend-item" }, swatch("dot"), "not compared yet"),
    ),
  );
  showSuggestions.addEventListener("change", () => onChange({ showSuggestions: showSuggestions.checked }));
  showHistory.addEventListener("change", () => onChange({ showHistory: showHistory.checked }));
  k.addEventListener("input", () => onChange({ k: Number(k.value) }));
  beta.addEventListener("input", () => onChange({ beta: Number(beta.value) }));

  let counted: readonly HistoryEdge[] | null = null;
  return {
    element,
    update(view, maxK, suggestions, history) {
      showSuggestions.checked = view.showSuggestions;
      showHistory.checked = view.showHistory;
      const max = String(Math.max(0, maxK));
      if (k.max !== max) k.max = max;
      const value = String(Math.min(view.k, maxK));
      if (k.value !== value) k.value = value;
      k.disabled = !view.showSuggestions || maxK === 0;
      text(kOut, value);
      const b = String(view.beta);
      if (beta.value !== b) beta.value = b;
      text(suggestionCount, `(${suggestions})`);
      // Given comparisons counted as distinct behaviour pairs (an edge each); counted again
      // only when the history changed, not on every hover or selection.
      if (history !== counted) {
        counted = history;
        text(historyCount, `(${new Set(history.map((e) => `${e.a}|${e.b}`)).size})`);
      }
    },
  };
}
