// The tutor starts a live class on a lab robot.
import { fetchJson } from "../../lib/transport.js";

const form = document.getElementById("lead-form");
form.addEventListener("submit", async (event) => {
  event.preventDefault();
  const data = new FormData(form);
  const course = data.get("course_id");
  try {
    const live = await fetchJson(`/api/tours/${form.dataset.tourId}/sessions`, { method: "POST",
      body: { robot: data.get("robot"), course_id: course ? Number(course) : null } });
    window.location.assign(`/tours/sessions/${live.id}`);
  } catch (error) {
    form.querySelector("[data-field=result]").textContent = error.message;
  }
});
