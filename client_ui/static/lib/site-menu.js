// The header's links behind a "Menu" button on a phone (they do not fit one row there), always open on wider
// screens. The page renders the menu open, so without this script every link is still shown.

const PHONE = window.matchMedia("(max-width: 480px)");
const menu = document.querySelector(".site-menu");

function fit() {
  if (menu) menu.open = !PHONE.matches;
}

fit();
PHONE.addEventListener("change", fit);
document.addEventListener("click", (event) => {
  if (PHONE.matches && menu?.open && !menu.contains(event.target)) menu.open = false;
});
