// The tutor's test editor: shows the experimental task's fields only for an experimental test, and only the
// fields of the chosen task kind; the question editor shows only the chosen kind's fields. Without JavaScript
// every field shows, labelled by kind; the server checks all.
const form = document.getElementById("exam-form");
if (form) {
  const kind = form.querySelector("[name=kind]");
  const taskKind = form.querySelector("[name=task_kind]");
  const task = document.getElementById("task-fields");
  const sync = () => {
    task.hidden = kind.value !== "experimental";
    for (const part of task.querySelectorAll("[data-task-kind]")) part.hidden = part.dataset.taskKind !== taskKind.value;
  };
  kind.addEventListener("change", sync);
  taskKind.addEventListener("change", sync);
  sync();
}

const questionForm = document.getElementById("question-form");
if (questionForm) {
  const kind = questionForm.querySelector("[name=kind]");
  const sync = () => {
    for (const part of questionForm.querySelectorAll("[data-question-kinds]")) {
      part.hidden = !part.dataset.questionKinds.split(" ").includes(kind.value);
    }
  };
  kind.addEventListener("change", sync);
  sync();
}
