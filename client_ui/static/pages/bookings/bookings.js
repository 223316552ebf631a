// The bookings page: times are laid out by the server in the zone named by ?tz=; this module makes that
// the browser's own zone (Intl) on first visit, and says which zone is shown. No rules live here.

import { t } from "../../lib/i18n.js";


function start() {
  const root = document.querySelector("#bookings[data-tz]");
  if (!root) return;
  const browserZone = Intl.DateTimeFormat().resolvedOptions().timeZone;
  const params = new URLSearchParams(location.search);
  if (browserZone && !params.has("tz") && root.dataset.tz !== browserZone) {
    params.set("tz", browserZone);
    location.replace(`${location.pathname}?${params}`);
    return;
  }
  const note = root.querySelector("#time-zone-source");
  if (note) {
    note.textContent = root.dataset.tz === browserZone
      ? t("(your browser's time zone)")
      : t("(your browser is set to {browserZone})", { browserZone });
  }
}

start();
