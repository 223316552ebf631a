// The usage page: reads the figures of the chosen course and days (/api/analytics/usage) and draws them: time per
// student, queue waits, the week-by-hour heat map, the robots' uptime and faults, the sessions; each with its CSV.
import { fetchJson } from "../../lib/transport.js";
import { h } from "../../lib/dom.js";
import { DATE_LOCALE, dateTime, fixed, number, t } from "../../lib/i18n.js";

const root = document.getElementById("analytics");
const form = document.getElementById("analytics-filters");
const field = (name) => root.querySelector(`[data-field="${name}"]`);
const offsetMin = -new Date().getTimezoneOffset();  // minutes east of UTC, as the API takes it

const KINDS = { turn: t("turn"), practice: t("practice robot"), plan_run: t("plan run"), exercise_run: t("exercise run"),
  test_attempt: t("test attempt"), experiment_trial: t("experiment trial"), class_session: t("class session") };
const ENDINGS = { turn_ended: t("turn ended"), handed_over: t("handed over"), robot_stopped: t("robot stopped"),
  superseded: t("another run began"), finished: t("finished"), ongoing: t("still going") };
const MAINTENANCE = { restart: t("restarts"), dock: t("returns to dock"), clear_map: t("cleared maps") };

/** A length of time in words: "1 h 05 min", "3 min 20 s", "12 s"; whole hours and minutes said shortly ("2 h",
 *  "30 min"). */
export function duration(seconds) {
  const s = Math.round(seconds);
  if (s >= 3600 && s % 3600 === 0) return t("{hours} h", { hours: s / 3600 });
  if (s >= 60 && s % 60 === 0 && s < 3600) return t("{minutes} min", { minutes: s / 60 });
  if (s >= 3600) return t("{hours} h {minutes} min", { hours: Math.floor(s / 3600), minutes: String(Math.floor((s % 3600) / 60)).padStart(2, "0") });
  if (s >= 60) return t("{minutes} min {seconds} s", { minutes: Math.floor(s / 60), seconds: String(s % 60).padStart(2, "0") });
  return t("{seconds} s", { seconds: s });
}

function binLabel(bin) {
  if (bin.high_s === 1) return t("no wait");
  if (bin.high_s === null) return t("{low} or more", { low: duration(bin.low_s) });
  return t("{low} to {high}", { low: duration(bin.low_s), high: duration(bin.high_s) });
}

function query() {
  const params = new URLSearchParams();
  const data = new FormData(form);
  for (const name of ["course_id", "from", "to"]) if (data.get(name)) params.set(name, data.get(name));
  params.set("utc_offset_min", String(offsetMin));
  return params;
}

/** el with the custom property name set through the CSSOM (the page's CSP refuses style attributes). */
function styled(el, name, value) {
  el.style.setProperty(name, value);
  return el;
}

function fill(tbody, rows) {
  tbody.replaceChildren(...rows);
}

function drawStudents(students) {
  const most = Math.max(1, ...students.map((s) => s.seconds));
  fill(root.querySelector(".analytics__students tbody"), students.map((s) => h("tr", {},
    h("td", { "data-label": t("Student") }, s.username),
    h("td", { "data-label": t("Sessions") }, number(s.sessions)),
    h("td", { "data-label": t("Time on robots") },
      styled(h("span", { class: "analytics__bar" }), "--share", (s.seconds / most).toFixed(3)), " ", // data, not text: a CSS value
      duration(s.seconds)))));
  root.querySelector('[data-empty="students"]').hidden = students.some((s) => s.sessions > 0);
}

function drawWaits(waits) {
  field("waits-summary").textContent = waits.count
    ? t("{count} turns granted: half waited {median} or less, nine in ten {p90} or less; the longest wait was {max} (mean {mean}).",
      { count: number(waits.count), median: duration(waits.median_s), p90: duration(waits.p90_s),
        max: duration(waits.max_s), mean: duration(waits.mean_s) })
    : t("No turn was granted in these days.");
  const most = Math.max(1, ...waits.bins.map((b) => b.count));
  fill(root.querySelector(".analytics__bars"), waits.bins.map((bin) => h("li", { class: "analytics__bin" },
    h("span", { class: "analytics__bin-label" }, binLabel(bin)),
    styled(h("span", { class: "analytics__bin-bar" }), "--share", (bin.count / most).toFixed(3)), // data, not text: a CSS value
    h("span", { class: "analytics__bin-count" }, number(bin.count)))));
}

function weekdayNames() {
  const format = new Intl.DateTimeFormat(DATE_LOCALE, { weekday: "short", timeZone: "UTC" });
  return [...Array(7).keys()].map((i) => format.format(new Date(Date.UTC(2024, 0, 1 + i))));  // 1 Jan 2024: a Monday
}

function drawHeatMap(grid) {
  const days = weekdayNames();
  const most = Math.max(0, ...grid.flat());
  const table = root.querySelector(".analytics__heat");
  table.querySelector("thead").replaceChildren(h("tr", {}, h("th", { scope: "col" }, ""),
    ...[...Array(24).keys()].map((hour) => h("th", { scope: "col" }, String(hour).padStart(2, "0")))));
  fill(table.querySelector("tbody"), grid.map((hours, day) => h("tr", {}, h("th", { scope: "row" }, days[day]),
    ...hours.map((minutes, hour) => {
      const words = t("{day} {hour}:00: {minutes} min", { day: days[day], hour: String(hour).padStart(2, "0"), minutes: fixed(minutes, 0) });
      const level = most > 0 ? minutes / most : 0;
      return styled(h("td", { title: words, "aria-label": words, "data-minutes": String(minutes),
        class: minutes > 0 ? "is-used" : "" }), "--level", level.toFixed(3)); // data, not text: a CSS value
    }))));
}

function drawRobots(robots) {
  fill(root.querySelector('[data-testid="robots-table"] tbody'), robots.map((r) => h("tr", { "data-robot": r.robot_name },
    h("td", { "data-label": t("Robot") }, r.robot_name),
    h("td", { "data-label": t("Sessions") }, number(r.sessions)),
    h("td", { "data-label": t("In use") }, duration(r.seconds_used)),
    h("td", { "data-label": t("Uptime") }, r.uptime_pct === null ? "—" : `${fixed(r.uptime_pct, 1)} %`),
    h("td", { "data-label": t("Faults") }, number(r.outages)),
    h("td", { "data-label": t("Down") }, duration(r.downtime_s)),
    h("td", { "data-label": t("Maintenance") }, Object.entries(r.maintenance)
      .map(([action, count]) => `${MAINTENANCE[action] || action}: ${number(count)}`).join(", ") || "—"))));
}

function drawSessions(sessions, total) {
  field("sessions-note").textContent = total > sessions.length
    ? t("The newest {shown} of {total} sessions; the CSV holds them all.", { shown: number(sessions.length), total: number(total) })
    : t("{total} sessions.", { total: number(total) });
  fill(root.querySelector('[data-testid="sessions-table"] tbody'), sessions.map((s) => h("tr", { "data-session": s.id },
    h("td", { "data-label": t("Started") }, dateTime(s.started_at)),
    h("td", { "data-label": t("Who") }, s.username),
    h("td", { "data-label": t("Robot") }, s.robot_name),
    h("td", { "data-label": t("Session") }, KINDS[s.kind] || s.kind),
    h("td", { "data-label": t("Length") }, duration(s.duration_s)),
    h("td", { "data-label": t("Commands") }, number(s.command_count)),
    h("td", { "data-label": t("Skills") }, number(s.skill_count)),
    h("td", { "data-label": t("Plans") }, number(s.plan_count)),
    h("td", { "data-label": t("Ended by") }, ENDINGS[s.end_reason] || (s.end_reason || "—").replaceAll("_", " ")))));
}

function drawLinks(params, data) {
  for (const link of root.querySelectorAll("[data-csv]")) link.href = `/api/analytics/${link.dataset.csv}.csv?${params}`;
  const xapi = field("xapi-link");
  const courseId = params.get("course_id");
  xapi.hidden = !courseId;
  field("xapi-choose").hidden = Boolean(courseId);
  if (courseId) {
    const rest = new URLSearchParams(params);
    rest.delete("course_id");
    xapi.href = `/api/analytics/courses/${encodeURIComponent(courseId)}/xapi?${rest}`;
  }
  const lrs = field("lrs");
  lrs.hidden = !data.xapi;
  if (data.xapi) {
    lrs.textContent = data.xapi.lrs
      ? t("Learning Record Store: {sent} statements sent, {pending} waiting, {failed} refused.", data.xapi)
        + (data.xapi.last_error ? ` ${t("Last problem: {error}", { error: data.xapi.last_error })}` : "")
      : t("No Learning Record Store is configured (TELELAB_XAPI_LRS_URL): statements are only downloaded.");
  }
}

async function show() {
  const params = query();
  const status = field("status");
  status.textContent = t("Loading…");
  root.dataset.state = "loading";
  let data;
  try {
    data = await fetchJson(`/api/analytics/usage?${params}`);
  } catch (error) {
    status.textContent = error.message;
    root.dataset.state = "error";
    return;
  }
  const seconds = data.students.reduce((sum, s) => sum + s.seconds, 0);
  field("summary").textContent = t("{from} to {to}: {sessions} sessions, {time} on robots, {turns} turns granted.", {
    from: data.window.from, to: data.window.to, sessions: number(data.sessions_total), time: duration(seconds),
    turns: number(data.waits.count) });
  if (!form.elements.from.value) form.elements.from.value = data.window.from;
  if (!form.elements.to.value) form.elements.to.value = data.window.to;
  drawStudents(data.students);
  drawWaits(data.waits);
  drawHeatMap(data.heat_map);
  drawRobots(data.robots);
  drawSessions(data.sessions, data.sessions_total);
  drawLinks(params, data);
  status.textContent = "";
  root.dataset.course = params.get("course_id") || "";
  root.dataset.state = "ready";
  history.replaceState(null, "", `?${new URLSearchParams([...params].filter(([k]) => k !== "utc_offset_min"))}`);
}

form.addEventListener("submit", (event) => {
  event.preventDefault();
  show();
});
form.querySelector('[data-field="course"]').addEventListener("change", () => show());
show();
