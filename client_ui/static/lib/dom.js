// Tiny helpers for building DOM from data without ever parsing data as HTML.

/**
 * Create an element. Strings among `children` become text nodes, so data is always escaped.
 * `attrs` keys: "class", "text", "hidden", "on<event>" handlers, and plain attributes.
 */
export function h(tag, attrs = {}, ...children) {
  const element = document.createElement(tag);
  for (const [name, value] of Object.entries(attrs)) {
    if (value === null || value === undefined || value === false) continue;
    if (name === "class") element.className = value;
    else if (name === "text") element.textContent = value;
    else if (name.startsWith("on") && typeof value === "function") element.addEventListener(name.slice(2), value);
    else element.setAttribute(name, value === true ? "" : String(value));
  }
  for (const child of children.flat()) {
    if (child === null || child === undefined || child === false) continue;
    element.append(child instanceof Node ? child : document.createTextNode(String(child)));
  }
  return element;
}

const adoptedStyles = new Set();

/** Add a panel's stylesheet to the page once; `url` is usually `new URL("./x.css", import.meta.url)`. */
export function adoptStylesheet(url) {
  const href = String(url);
  if (adoptedStyles.has(href)) return;
  adoptedStyles.add(href);
  document.head.append(h("link", { rel: "stylesheet", href }));
}

/** Define a custom element once (modules may be imported by several pages). */
export function defineOnce(name, elementClass) {
  if (!customElements.get(name)) customElements.define(name, elementClass);
}
