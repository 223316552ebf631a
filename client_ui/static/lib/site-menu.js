// The header's links behind a "Menu" button on a phone (they do not fit one row there), always open on wider
// screens. The page renders the menu open, so without this script every link is still shown.

const PHONE = window.matchMedia("(max-width: 480px)");
const menu = document.querySelector(".site-menu");

function fit() {
  if (menu) menu.open = !PHONE.matches;
}

fit();
PHONE.addEventListener("change", fit);

// The language picker changes the language as soon as another is chosen; its button is for pages without scripts
// (and takes room the header needs on a laptop's width).
for (const picker of document.querySelectorAll(".language-picker")) {
  const button = picker.querySelector('button[type="submit"]');
  const select = picker.querySelector("select");
  if (!button || !select) continue;
  button.hidden = true;
  select.addEventListener("change", () => picker.requestSubmit());
}
document.addEventListener("click", (event) => {
  if (PHONE.matches && menu?.open && !menu.contains(event.target)) menu.open = false;
});
