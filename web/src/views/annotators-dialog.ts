/**
 * The owner's "Annotators" dialog (issue 21): add a person by name, copy the link that
 * opens this session with their own token (shown once: the server keeps only what checks
 * it), and remove a person, which ends their link; their judgements stay. Opens under the
 * status bar; Escape or × closes it and gives the focus back to "Annotators".
 */
import type { Annotator, AnnotatorCreated } from "../api";
import { OWNER_ID } from "../lib/annotators";
import type { PeopleState } from "../state";
import { badge } from "./people";
import { h, memo, text } from "./dom";

export interface AnnotatorsDialogData {
  open: boolean;
  people: readonly Annotator[];
  colours: ReadonlyMap<string, string>;
  state: PeopleState;
  /** The page's address, which a link the server gives relative is resolved against. */
  base: string;
}

export interface AnnotatorsDialogHandlers {
  add(name: string): Promise<boolean>;
  remove(id: string): void;
  close(): void;
}

interface View {
  box: HTMLElement;
  name: HTMLInputElement;
  add: HTMLButtonElement;
  error: HTMLElement;
  created: HTMLElement;
  createdLabel: HTMLElement;
  link: HTMLInputElement;
  copy: HTMLButtonElement;
  copied: HTMLElement;
  list: HTMLUListElement;
  none: HTMLElement;
  handlers: AnnotatorsDialogHandlers | null;
  data: AnnotatorsDialogData | null;
  wasOpen: boolean;
  confirm: { id: string; until: number } | null;
  shownCreated: AnnotatorCreated | null;
  /** What the list shows, so it is rebuilt only when that changes (a focused button stays). */
  listKey: string;
}

const views = new WeakMap<Element, View>();
const CONFIRM_MS = 4000;

/** A link as the person will open it: absolute, against the page's own address. */
export function absoluteLink(link: string, base: string): string {
  try {
    return new URL(link, base).toString();
  } catch {
    return link;
  }
}

export function renderAnnotatorsDialog(
  element: HTMLElement,
  data: AnnotatorsDialogData,
  handlers: AnnotatorsDialogHandlers,
): void {
  const view = memo(views, element, () => build(element));
  view.handlers = handlers;
  view.data = data;
  element.hidden = !data.open;
  if (!data.open) {
    view.wasOpen = false;
    return;
  }
  if (!view.wasOpen) {
    view.wasOpen = true;
    view.name.focus();
  }
  view.add.disabled = data.state.busy;
  view.error.hidden = !data.state.error;
  text(view.error, data.state.error ?? "");
  const c = data.state.created;
  view.created.hidden = !c;
  if (c && c !== view.shownCreated) {
    view.shownCreated = c;
    text(view.createdLabel, `${c.name}'s link (shown this once: it holds their access token)`);
    view.link.value = absoluteLink(c.link, data.base);
    view.copied.hidden = true;
  }
  const others = data.people.filter((p) => p.id !== OWNER_ID);
  view.none.hidden = others.length > 0;
  const confirming = view.confirm && view.confirm.until > Date.now() ? view.confirm.id : null;
  const key = JSON.stringify([others.map((p) => [p.id, p.name, p.comparisons, data.colours.get(p.id)]), data.state.busy, confirming]);
  if (key === view.listKey) return;
  view.listKey = key;
  view.list.replaceChildren(
    ...others.map((p) => {
      const asking = confirming === p.id;
      const remove = h(
        "button",
        {
          type: "button",
          class: `small remove${asking ? " confirm" : ""}`,
          "aria-label": asking ? `Click again to remove ${p.name}` : `Remove ${p.name}`,
          "data-id": p.id,
          disabled: data.state.busy,
        },
        asking ? "Click again" : "Remove",
      );
      remove.addEventListener("click", () => {
        if (view.confirm?.id === p.id && view.confirm.until > Date.now()) {
          view.confirm = null;
          view.handlers?.remove(p.id);
          return;
        }
        view.confirm = { id: p.id, until: Date.now() + CONFIRM_MS };
        // The list is rebuilt: the focus stays on this person's button if it was there.
        const again = () => {
          const active = document.activeElement;
          const focused = active instanceof HTMLElement && element.contains(active) && active.dataset.id === p.id;
          renderAnnotatorsDialog(element, view.data!, view.handlers!);
          if (focused) element.querySelector<HTMLButtonElement>(`.remove[data-id="${CSS.escape(p.id)}"]`)?.focus();
        };
        again();
        // Not clicked again in time: the button reads "Remove" again.
        window.setTimeout(() => {
          if (view.confirm?.id === p.id && view.confirm.until <= Date.now()) again();
        }, CONFIRM_MS + 50);
      });
      return h(
        "li",
        { class: "person-item", "data-id": p.id },
        badge(p.name, data.colours.get(p.id) ?? "#344054"),
        h("span", { class: "person-name" }, p.name),
        h("span", { class: "muted num" }, `${p.comparisons} comparisons`),
        remove,
      );
    }),
  );
}

async function copy(view: View): Promise<void> {
  const value = view.link.value;
  try {
    await navigator.clipboard.writeText(value);
  } catch {
    // No clipboard permission (an insecure origin, a test browser): select it to copy by hand.
    view.link.select();
    document.execCommand?.("copy");
  }
  view.copied.hidden = false;
}

function build(element: HTMLElement): View {
  element.classList.add("people-dialog");
  element.setAttribute("role", "dialog");
  element.setAttribute("aria-labelledby", "people-dialog-title");
  const name = h("input", {
    type: "text",
    class: "people-name-input",
    maxlength: 100,
    autocomplete: "off",
    placeholder: "e.g. Ann",
    "aria-label": "Name of the person to add",
  });
  const add = h("button", { type: "submit", class: "primary" }, "Add");
  const error = h("p", { class: "people-error", role: "alert", hidden: true });
  const createdLabel = h("label", { class: "people-link-label", for: "people-link" });
  const link = h("input", { id: "people-link", type: "text", readonly: true, class: "people-link" });
  const copyButton = h("button", { type: "button" }, "Copy link");
  const copied = h("span", { class: "muted", role: "status", hidden: true }, "Copied");
  const created = h(
    "div",
    { class: "people-created", hidden: true },
    createdLabel,
    h("div", { class: "people-link-row" }, link, copyButton, copied),
  );
  const list = h("ul", { class: "people-list", "aria-label": "People of this session" });
  const none = h("p", { class: "muted" }, "Nobody else yet.");
  const close = h("button", { type: "button", class: "ghost small", "aria-label": "Close" }, "×");
  const form = h("form", { class: "people-form" }, name, add);
  element.replaceChildren(
    h(
      "div",
      { class: "people-dialog-card" },
      h("header", { class: "people-dialog-head" }, h("h2", { id: "people-dialog-title" }, "Annotators"), close),
      h(
        "p",
        { class: "muted people-note" },
        "Each person opens this session with a link of their own. Their answers teach the same " +
          "agent; ending the round and the settings stay yours.",
      ),
      form,
      error,
      created,
      list,
      none,
    ),
  );
  const view: View = {
    box: element,
    name,
    add,
    error,
    created,
    createdLabel,
    link,
    copy: copyButton,
    copied,
    list,
    none,
    handlers: null,
    data: null,
    wasOpen: false,
    confirm: null,
    shownCreated: null,
    listKey: "",
  };
  form.addEventListener("submit", (event) => {
    event.preventDefault();
    void view.handlers?.add(name.value).then((ok) => {
      if (ok) name.value = "";
    });
  });
  copyButton.addEventListener("click", () => void copy(view));
  link.addEventListener("focus", () => link.select());
  close.addEventListener("click", () => view.handlers?.close());
  element.addEventListener("keydown", (event) => {
    if (event.key === "Escape") {
      event.stopPropagation();
      view.handlers?.close();
    }
  });
  return view;
}
