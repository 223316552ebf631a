// A tutor's form on an exercise's page: attach the exercise to a course they teach as a test (a deadline and points;
// POST /api/courses/<id>/exercises). Again for the same course moves its deadline and points.
import { fetchJson } from "../../lib/transport.js";
import { number, t } from "../../lib/i18n.js";

const form = document.querySelector("[data-slot=attach]");
const status = form.querySelector("[data-field=attach-status]");
const attached = form.querySelector("[data-slot=attached]");

form.addEventListener("submit", async (event) => {
  event.preventDefault();
  const course = form.elements.course_id.selectedOptions[0];
  const button = form.querySelector("button[type=submit]");
  button.disabled = true;
  status.dataset.kind = "";
  try {
    // The field holds a UTC time without its zone (the label says so): the API reads it with Z.
    const answer = await fetchJson(`/api/courses/${encodeURIComponent(course.value)}/exercises`, { method: "POST",
      body: { slug: form.dataset.slug, deadline_at: `${form.elements.deadline_at.value}Z`,
              points: Number(form.elements.points.value) } });
    const said = t("A test of {course}: deadline {deadline} UTC, {points} points.", { course: course.textContent,
      deadline: answer.test.deadline_at.slice(0, 16).replace("T", " "), points: number(answer.test.points) });
    status.textContent = t("Attached. {test}", { test: said });
    // Attached again to the same course: its new terms replace the old ones.
    let item = attached.querySelector(`li[data-course="${CSS.escape(course.value)}"]`);
    if (!item) {
      item = document.createElement("li");
      item.dataset.course = course.value;
      attached.append(item);
    }
    item.textContent = said;
  } catch (error) {
    status.textContent = error.message;
    status.dataset.kind = "error";
  } finally {
    button.disabled = false;
  }
});
