// The console's arrangeable grid: each panel sits in a frame (a labelled region with move, resize and
// hide buttons), a "Panels" menu shows and hides them, and the layout is saved per user.
// Panels are grouped in tabs (the descriptor's `tab`: Drive, Navigate, Sense, Chat) so that one view fits
// a screen; a panel that asks for attention ("panel-attention" event) while its tab is not shown counts
// in a badge on that tab.
// The rules of the arrangement are the pure reducer in layout.js; this module only renders it.

import { h } from "../dom.js";
import { layoutReducer, normalizeLayout, serializeLayout } from "../layout.js";
import { t } from "../i18n.js";

const SAVE_DELAY_MS = 400;
const TAB_NAMES = { drive: t("Drive"), navigate: t("Navigate"), sense: t("Sense"), chat: t("Chat") };
const FIRST_TAB = "drive";

/**
 * Frames for the panels in `grid`, a menu in `menuHost`.
 * `save(value)` stores the layout (returns a promise); `onSaveError(error)` reports a failed save.
 */
const HELP_SHOWN_CHARS = 140;

/** A panel's help: whole when short; else its first sentence, the rest a click away (seven skills' paragraphs made
 *  the Navigate tab four screens tall). */
function frameHelp(help) {
  const cut = help.search(/\.\s/);
  if (help.length <= HELP_SHOWN_CHARS || cut < 0) return h("p", { class: "panel-frame__help", text: help });
  return h("details", { class: "panel-frame__help" },
    h("summary", { text: help.slice(0, cut + 1) }), h("p", { text: help.slice(cut + 2) }));
}

export class ConsoleLayout {
  #grid;
  #menuList;
  #menuCount;
  #frames = new Map(); // id -> {frame, descriptor, buttons, checkbox}
  #layout = { order: [], hidden: [], spans: {} };
  #defaultSpans = {};
  #save;
  #onSaveError;
  #saveTimer = 0;
  #summary;
  #tabList;
  #tabs = new Map(); // tab -> {button, badge, unread}
  #activeTab = FIRST_TAB;
  #tabbed;

  // tabs: false puts every panel in one view (a teaching page shows the few panels it asked for side by side).
  constructor(grid, menuHost, { save = null, onSaveError = () => {}, tabs = true } = {}) {
    this.#grid = grid;
    this.#tabbed = tabs;
    this.#tabList = h("div", { class: "console__tabs", role: "tablist", "aria-label": t("Console views"),
      hidden: !tabs });
    this.#tabList.addEventListener("keydown", (event) => this.#onTabKey(event));
    grid.before(this.#tabList);
    this.#save = save;
    this.#onSaveError = onSaveError;
    this.#menuList = h("ul", { class: "panels-menu__list" });
    this.#menuCount = h("span", { class: "panels-menu__count", "data-field": "hidden-count" });
    this.#summary = h("summary", { class: "button panels-menu__button" }, t("Panels"), this.#menuCount);
    menuHost.append(h("details", { class: "panels-menu", "data-testid": "panels-menu" },
      this.#summary,
      h("div", { class: "panels-menu__body" },
        h("p", { class: "panels-menu__hint", text: t("Show or hide panels:") }),
        this.#menuList,
        h("button", { type: "button", class: "button panels-menu__reset", "data-layout": "reset", text: t("Reset layout"),
          onclick: () => this.#dispatch({ type: "reset", ids: this.ids, defaultSpans: this.#defaultSpans }) }))));
  }

  get ids() {
    return [...this.#frames.keys()];
  }

  get layout() {
    return this.#layout;
  }

  /** The frame of a panel id (for notices), or undefined. */
  frameOf(id) {
    return this.#frames.get(id)?.frame;
  }

  /** Is the panel shown now (not hidden, and on the tab in view)? */
  isShown(id) {
    const entry = this.#frames.get(id);
    return Boolean(entry) && !this.#layout.hidden.includes(id) && entry.tab === this.#activeTab;
  }

  /** The tab in view. */
  get activeTab() {
    return this.#activeTab;
  }

  /** Brings a tab into view and clears its unread badge. */
  showTab(tab) {
    if (!this.#tabs.has(tab)) return;
    this.#activeTab = tab;
    for (const [name, entry] of this.#tabs) {
      const active = name === tab;
      entry.button.setAttribute("aria-selected", String(active));
      entry.button.tabIndex = active ? 0 : -1;
      if (active) this.#setUnread(entry, 0);
    }
    for (const { frame, tab: frameTab } of this.#frames.values()) {
      frame.classList.toggle("panel-frame--other-tab", frameTab !== tab);
    }
    this.#grid.dataset.tab = tab;
  }

  #ensureTab(tab) {
    if (this.#tabs.has(tab)) return;
    const badge = h("span", { class: "console__tab-badge", "data-field": "unread", hidden: true });
    const button = h("button", {
      type: "button", role: "tab", class: "console__tab", id: `console-tab-${tab}`, "data-tab": tab,
      "aria-selected": "false", "aria-controls": this.#grid.id || null, tabindex: "-1",
      onclick: () => this.showTab(tab),
    }, TAB_NAMES[tab] ?? tab[0].toUpperCase() + tab.slice(1), badge);
    this.#tabs.set(tab, { button, badge, unread: 0 });
    const order = Object.keys(TAB_NAMES);
    const rank = (name) => (order.includes(name) ? order.indexOf(name) : order.length);
    const after = [...this.#tabs.keys()].filter((name) => name !== tab && rank(name) > rank(tab))
      .sort((a, b) => rank(a) - rank(b))[0];
    if (after) this.#tabs.get(after).button.before(button);
    else this.#tabList.append(button);
  }

  #setUnread(entry, count) {
    entry.unread = count;
    entry.badge.hidden = count === 0;
    entry.badge.textContent = count ? String(count) : "";
    entry.badge.setAttribute("aria-label", t("{count} new", { count }));
  }

  #onTabKey(event) {
    const names = [...this.#tabList.querySelectorAll('[role="tab"]')].map((button) => button.dataset.tab);
    const step = { ArrowRight: 1, ArrowLeft: -1 }[event.key];
    if (!step) return;
    event.preventDefault();
    const next = names[(names.indexOf(this.#activeTab) + step + names.length) % names.length];
    this.showTab(next);
    this.#tabs.get(next).button.focus();
  }

  /** Add a frame holding `panel` for a checked descriptor; `span` is its default width. */
  addPanel(descriptor, panel, span = 1) {
    const id = descriptor.id;
    const titleId = `panel-title-${id}`;
    const title = descriptor.title;
    const button = (action, glyph, label, extra = {}) => h("button", {
      type: "button", class: "panel-frame__tool", "data-layout": action, "aria-label": label, title: label, ...extra,
      onclick: () => this.#onTool(id, action),
    }, h("span", { "aria-hidden": "true", text: glyph }));
    const buttons = {
      up: button("up", "↑", t("Move {title} up", { title })),
      down: button("down", "↓", t("Move {title} down", { title })),
      span: button("span", "⇔", t("Wide {title}", { title }), { "aria-pressed": "false" }),
      hide: button("hide", "×", t("Hide {title}", { title })),
    };
    const notice = h("p", { class: "panel-frame__notice", role: "status", "data-field": "panel-notice", hidden: true });
    const frame = h("section", { class: "panel-frame", role: "region", "aria-labelledby": titleId,
      "data-panel-id": id, "data-kind": descriptor.kind },
      h("div", { class: "panel-frame__bar" },
        h("h2", { class: "panel-frame__title", id: titleId, text: title }),
        h("div", { class: "panel-frame__tools", role: "group", "aria-label": t("Arrange {title}", { title }) },
          buttons.up, buttons.down, buttons.span, buttons.hide)),
      descriptor.help ? frameHelp(descriptor.help) : null,
      notice,
      panel);
    const checkbox = h("input", { type: "checkbox", checked: true, id: `show-panel-${id}`, "data-show-panel": id,
      onchange: (event) => this.#dispatch({ type: event.target.checked ? "show" : "hide", id }) });
    this.#menuList.append(h("li", {}, h("label", { for: `show-panel-${id}` }, checkbox, ` ${title}`)));
    const tab = this.#tabbed && typeof descriptor.tab === "string" && descriptor.tab ? descriptor.tab : FIRST_TAB;
    this.#ensureTab(tab);
    frame.dataset.tab = tab;
    frame.addEventListener("panel-attention", () => {
      const entry = this.#tabs.get(tab);
      if (tab !== this.#activeTab) this.#setUnread(entry, entry.unread + 1);
    });
    this.#frames.set(id, { frame, descriptor, buttons, checkbox, notice, notices: 0, tab });
    this.#defaultSpans[id] = span;
    this.#grid.append(frame);
    return frame;
  }

  /** A visible notice in place of a panel that could not be shown. */
  addNotice(text) {
    const notice = h("section", { class: "panel-frame panel-frame--broken", role: "region",
      "aria-label": t("A panel that could not be shown"), "data-notice": "bad-descriptor" },
      h("p", { class: "alert alert--error", text }));
    this.#grid.append(notice);
    return notice;
  }

  /** A short line in a panel's frame, e.g. "1 unreadable message ignored". */
  notify(id, text) {
    const entry = this.#frames.get(id);
    if (!entry) return;
    entry.notices += 1;
    entry.notice.textContent = entry.notices > 1 ? t("{text} ({notices} so far)", { text, notices: entry.notices }) : text;
    entry.notice.hidden = false;
  }

  /** Apply a saved layout (or none) to the frames placed so far. */
  restore(saved) {
    this.#layout = normalizeLayout(saved, this.ids, this.#defaultSpans);
    this.#render();
    this.showTab(this.#tabs.has(FIRST_TAB) ? FIRST_TAB : [...this.#tabs.keys()][0]);
  }

  #onTool(id, action) {
    if (action === "up" || action === "down") this.#dispatch({ type: "move", id, by: action === "up" ? -1 : 1 }, id, action);
    else if (action === "span") this.#dispatch({ type: "resize", id, span: this.#layout.spans[id] === 2 ? 1 : 2 }, id, action);
    else if (action === "hide") {
      this.#dispatch({ type: "hide", id });
      this.#summary.focus(); // the hidden panel's button is gone; the menu is where it can come back
    }
  }

  #dispatch(action, focusId = null, focusAction = null) {
    const next = layoutReducer(this.#layout, action);
    if (next === this.#layout) return;
    this.#layout = next;
    this.#render();
    if (focusId) this.#frames.get(focusId)?.buttons[focusAction]?.focus();
    this.#scheduleSave();
  }

  #render() {
    const { order, hidden, spans } = this.#layout;
    const visible = order.filter((id) => !hidden.includes(id));
    // Frames follow the layout's order; notices about broken descriptors, never moved, end up first.
    for (const id of order) {
      const entry = this.#frames.get(id);
      this.#grid.append(entry.frame);
      entry.frame.hidden = hidden.includes(id);
      entry.frame.dataset.span = String(spans[id] ?? 1);
      entry.buttons.span.setAttribute("aria-pressed", String(spans[id] === 2));
      entry.buttons.up.disabled = visible[0] === id;
      entry.buttons.down.disabled = visible[visible.length - 1] === id;
      entry.checkbox.checked = !hidden.includes(id);
    }
    this.#menuCount.textContent = hidden.length ? t(" ({length} hidden)", { length: hidden.length }) : "";
  }

  #scheduleSave() {
    if (!this.#save) return;
    clearTimeout(this.#saveTimer);
    this.#saveTimer = setTimeout(() => {
      this.#save(serializeLayout(this.#layout)).catch((error) => this.#onSaveError(error));
    }, SAVE_DELAY_MS);
  }
}
