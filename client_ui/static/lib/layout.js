// Pure layout state of the console: panel order, hidden panels and width (1 or 2 columns).
// The console renders it; the preferences API stores it per user as {version, order, hidden, spans}.

export const LAYOUT_VERSION = 1;
const SPANS = new Set([1, 2]);

/** A layout for the panel ids the server sent, keeping what a saved layout says about known ids. */
export function normalizeLayout(saved, ids, defaultSpans = {}) {
  const known = new Set(ids);
  const savedOrder = Array.isArray(saved?.order) ? saved.order.filter((id) => known.has(id)) : [];
  const order = [...new Set(savedOrder)];
  // Panels new since the layout was saved go after the panel the server puts before them.
  ids.forEach((id, index) => {
    if (order.includes(id)) return;
    const before = ids.slice(0, index).reverse().find((other) => order.includes(other));
    order.splice(before === undefined ? 0 : order.indexOf(before) + 1, 0, id);
  });
  const hidden = Array.isArray(saved?.hidden) ? [...new Set(saved.hidden.filter((id) => known.has(id)))] : [];
  const spans = {};
  for (const id of ids) {
    const span = Number(saved?.spans?.[id] ?? defaultSpans[id] ?? 1);
    spans[id] = SPANS.has(span) ? span : 1;
  }
  return { order, hidden, spans };
}

/** The next layout after one action: move (by -1/+1 among visible panels), hide, show, resize, reset. */
export function layoutReducer(layout, action) {
  switch (action.type) {
    case "move": {
      const visible = layout.order.filter((id) => !layout.hidden.includes(id));
      const at = visible.indexOf(action.id);
      const target = visible[at + Math.sign(action.by)];
      if (at < 0 || target === undefined) return layout;
      const order = [...layout.order];
      const from = order.indexOf(action.id);
      const to = order.indexOf(target);
      [order[from], order[to]] = [order[to], order[from]];
      return { ...layout, order };
    }
    case "hide":
      return layout.hidden.includes(action.id) || !layout.order.includes(action.id)
        ? layout : { ...layout, hidden: [...layout.hidden, action.id] };
    case "show":
      return { ...layout, hidden: layout.hidden.filter((id) => id !== action.id) };
    case "resize":
      return SPANS.has(action.span) && layout.order.includes(action.id)
        ? { ...layout, spans: { ...layout.spans, [action.id]: action.span } } : layout;
    case "reset":
      return normalizeLayout(null, action.ids, action.defaultSpans);
    default:
      return layout;
  }
}

/** What is stored in the user's preferences. */
export function serializeLayout(layout) {
  return { version: LAYOUT_VERSION, order: layout.order, hidden: layout.hidden, spans: layout.spans };
}
