// The invitation link page: a button copies the link (the clipboard API, or the link selected for Ctrl+C
// where the browser refuses it) and says which happened.

import { t } from "../../lib/i18n.js";

const link = document.getElementById("invitation-link");
const button = document.querySelector("[data-action=copy-link]");
const status = document.querySelector("[data-field=copy-status]");

function selectLink() {
  const range = document.createRange();
  range.selectNodeContents(link);
  window.getSelection().removeAllRanges();
  window.getSelection().addRange(range);
}

button.hidden = false;
button.addEventListener("click", async () => {
  try {
    await navigator.clipboard.writeText(link.textContent.trim());
    status.textContent = t("Link copied. Paste it into your message.");
  } catch {
    selectLink();
    status.textContent = t("The browser did not allow copying: the link is selected, press Ctrl+C (⌘C on a Mac).");
  }
});
