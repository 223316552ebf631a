// A course's leaderboard of an exercise (GET /api/courses/<id>/exercises/<slug>/leaderboard): the ranked students,
// the viewer's own row marked, and for the course's tutors whether it is open with the button that opens or closes
// it (PUT the same address). Who may read it and every mark are the server's; a closed one's refusal is said here.
import { fetchJson } from "../../lib/transport.js";
import { h } from "../../lib/dom.js";
import { dateTime, isSingular, number, t } from "../../lib/i18n.js";

const root = document.getElementById("leaderboard");
const address = `/api/courses/${encodeURIComponent(root.dataset.course)}/exercises/${encodeURIComponent(root.dataset.slug)}/leaderboard`;
const field = (name) => root.querySelector(`[data-field="${name}"]`);
const control = root.querySelector("[data-slot=control]");
const toggle = root.querySelector("[data-action=toggle]");
const table = root.querySelector("[data-slot=standings]");
const MOMENT = { day: "numeric", month: "short", hour: "2-digit", minute: "2-digit" };  // short enough for a phone

/** A moment as MOMENT writes it, with its year when that is not this one (a deadline a year away is not today). */
function moment(iso) {
  const sameYear = new Date(iso).getFullYear() === new Date().getFullYear();
  return dateTime(iso, sameYear ? MOMENT : { ...MOMENT, year: "numeric" });
}

function say(text, kind = "") {
  field("status").textContent = text;
  field("status").dataset.kind = kind;
}

function markText(row, points) {
  return t("{mark} of {points} points ({percent})", { mark: number(row.mark, { maximumFractionDigits: 2 }),
    points: number(points, { maximumFractionDigits: 2 }), percent: number(row.fraction, { style: "percent" }) });
}

function drawControl(board) {
  control.hidden = !board.may_open;
  if (!board.may_open) return;
  field("state").textContent = board.open
    ? t("Open: the course's students see this leaderboard.")
    : t("Closed: only the course's tutors see it; its students read that it is closed.");
  toggle.textContent = board.open ? t("Close it to the students") : t("Open it to the students");
  toggle.dataset.open = String(board.open);
}

function drawStandings(board) {
  table.querySelector("tbody").replaceChildren(...board.standings.map((row) => h("tr",
    { class: row.you ? "leaderboard__you" : null, "aria-current": row.you ? "true" : null },
    h("td", { class: "leaderboard__rank" }, number(row.rank)),
    h("td", { class: "leaderboard__name" }, row.you ? t("{name} (you)", { name: row.username }) : row.username),
    h("td", { class: "leaderboard__mark" }, markText(row, board.points)),
    h("td", { class: "leaderboard__reached", "data-label": t("Reached") },
      h("time", { datetime: row.reached_at }, moment(row.reached_at))))));
  table.hidden = board.standings.length === 0;
  const count = board.standings.length;
  const mine = board.standings.find((row) => row.you);
  if (count === 0) say(t("No student of the course has a graded submission before the deadline yet."));
  else if (mine) say(t("You are number {rank} of {count}.", { rank: number(mine.rank), count: number(count) }));
  else if (board.may_open) say("");
  else say(t("You have no graded submission before the deadline yet, so you are not ranked."));
  const unranked = field("unranked");
  unranked.hidden = board.unranked === 0;
  unranked.textContent = isSingular(board.unranked)
    ? t("{count} student of the course has no graded submission before the deadline and is not listed.",
      { count: number(board.unranked) })
    : t("{count} students of the course have no graded submission before the deadline and are not listed.",
      { count: number(board.unranked) });
}

function draw(board) {
  drawControl(board);
  field("terms").hidden = false;
  field("terms").textContent = t("A mark is a student's best graded submission begun before {deadline}; equal marks rank by who reached theirs first.",
    { deadline: moment(board.deadline_at) });
  drawStandings(board);
}

async function load() {
  try {
    draw(await fetchJson(address));
  } catch (error) {
    table.hidden = true;
    // A closed leaderboard is not a fault: the sentence reads as a notice, not as an error.
    say(error.message, error.code === "leaderboard_closed" ? "closed" : "error");
  }
}

// While the change is sent the button says it is busy without being disabled: a disabled button loses the focus,
// and a keyboard user would have to find it again.
toggle.addEventListener("click", async () => {
  if (toggle.getAttribute("aria-disabled") === "true") return;
  toggle.setAttribute("aria-disabled", "true");
  try {
    await fetchJson(address, { method: "PUT", body: { open: toggle.dataset.open !== "true" } });
    await load();
  } catch (error) {
    say(error.message, "error");
  } finally {
    toggle.removeAttribute("aria-disabled");
  }
});

load();
