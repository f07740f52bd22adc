/** Tiny DOM helpers shared by the views. */

type Attrs = Record<string, string | number | boolean | null | undefined>;
type Child = Node | string | null | undefined | false;

/** Creates an element: attributes (false/null/undefined skipped), then children. */
export function h<K extends keyof HTMLElementTagNameMap>(
  tag: K,
  attrs: Attrs = {},
  ...children: Child[]
): HTMLElementTagNameMap[K] {
  const el = document.createElement(tag);
  setAttrs(el, attrs);
  for (const c of children) if (c !== null && c !== undefined && c !== false) el.append(c);
  return el;
}

export const SVG_NS = "http://www.w3.org/2000/svg";

export function s<K extends keyof SVGElementTagNameMap>(
  tag: K,
  attrs: Attrs = {},
  ...children: Child[]
): SVGElementTagNameMap[K] {
  const el = document.createElementNS(SVG_NS, tag);
  setAttrs(el, attrs);
  for (const c of children) if (c !== null && c !== undefined && c !== false) el.append(c);
  return el;
}

export function setAttrs(el: Element, attrs: Attrs): void {
  for (const [key, value] of Object.entries(attrs)) {
    if (value === false || value === null || value === undefined) el.removeAttribute(key);
    else el.setAttribute(key, value === true ? "" : String(value));
  }
}

/** Sets text only when it changed (keeps screen readers and layout quiet). */
export function text(el: Element, value: string): void {
  if (el.textContent !== value) el.textContent = value;
}

/** Toggles an attribute-backed boolean (disabled, hidden, aria-pressed…) only on change. */
export function attr(el: Element, name: string, value: string | null): void {
  if (value === null) {
    if (el.hasAttribute(name)) el.removeAttribute(name);
  } else if (el.getAttribute(name) !== value) el.setAttribute(name, value);
}

/** A keyboard-shortcut hint. */
export function kbd(...keys: string[]): HTMLElement {
  const span = h("span", { class: "keys", "aria-hidden": "true" });
  for (const k of keys) span.append(h("kbd", {}, k));
  return span;
}

/** Per-element memory of a view: built on first render, reused after. */
export function memo<T>(store: WeakMap<Element, T>, el: Element, build: () => T): T {
  let v = store.get(el);
  if (!v) {
    v = build();
    store.set(el, v);
  }
  return v;
}
