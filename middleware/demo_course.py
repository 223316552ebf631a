"""The demo course `telelab up` seeds, so every journey can be walked at once on a fresh lab.

"Mobile robotics (demo)": taught by the demo `tutor`, with the demo `student` enrolled, a weekly booking
allowance and a turn length; a small question bank; an open practice quiz, a timed theoretical test and an
experimental test on lab-1, both open now for a long window; and the course's lab survey (the demo tutor wrote
it: the 2003 paper's seven statements and one rated from "Not at all" to "A great deal"), already answered by
three demo classmates (disabled accounts that exist for their answers alone), so the tutor sees its charts
(shown from MIN_RESPONDENTS answers on) while the demo student can still answer it.
Beside it, its Spanish twin "Robótica móvil (demo)" (seed_spanish_demo_course): the same questions, tests and
survey written in Spanish, the same grading, the demo student enrolled and the survey answered by three
Spanish-speaking classmates, so a student who reads the lab in Spanish finds every kind of demo content in Spanish.
Everything goes through the courses and assessment services, so the seed obeys the same validation as a
tutor's forms.

The course's code marks the seed as done: a start that finds the course changes nothing, so what the tutor
has since changed (a student removed, a test edited or deleted) is never undone, and nothing is duplicated.
The classmates' accounts mark theirs: a course seeded before them gets them once.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from datetime import UTC, datetime, timedelta
from typing import Any, TypeVar

from sqlalchemy import select
from sqlalchemy.orm import Session

from middleware.accounts.services import set_active_by_name
from middleware.assessment import bank, survey
from middleware.assessment.schemas import SURVEY_ITEMS, parse_exam, parse_question, parse_survey
from middleware.assessment.survey_statements import parse_statements
from middleware.auth.services import create_user, find_user, generate_password
from middleware.courses import services as courses
from middleware.courses.schemas import CourseSettings
from middleware.exercises import leaderboard
from middleware.exercises import services as exercises
from middleware.experiment import protocol as experiment_protocol
from middleware.experiment import services as experiment
from middleware.models import Course, Role
from middleware.plans.demo_plans import seed_demo_plans

DEMO_COURSE_CODE = "DEMO-ROBOTICS"
DEMO_COURSE_TITLE = "Mobile robotics (demo)"
DEMO_ALLOWANCE_MIN = 120  # per week: four 30-minute slots
DEMO_TURN_LENGTH_S = 300
DEMO_ROBOT = "lab-1"
T = TypeVar("T")
OPEN_FOR = timedelta(days=365)  # the timed tests stay open long enough for any demo

# Facts of the simulated robot (skill_server/sim): 16 sonars, a 181-beam laser over 180 degrees up to 8 m.
DEMO_QUESTIONS: list[dict[str, Any]] = [
    {"kind": "single", "prompt": "Why does the odometry estimate drift away from the robot's true pose?",
     "choices": ["The wheels slip and their measured turns carry small errors that add up",
                 "The laser is too slow", "The camera is not calibrated"], "correct": 0,
     "topics": ["odometry"]},
    {"kind": "numeric", "prompt": "How many sonars ring the lab robot?", "value": 16, "tolerance": 0,
     "topics": ["sensors", "sonar"]},
    {"kind": "numeric", "prompt": "What is the laser's maximum range?", "value": 8, "tolerance": 0.5, "unit": "m",
     "topics": ["laser", "sensors"]},
    {"kind": "multiple", "prompt": "Which sensors measure distances to obstacles?",
     "choices": ["Sonar", "Laser", "Wheel encoders", "Camera (alone)"], "correct": [0, 1],
     "topics": ["sensors"]},
    {"kind": "single", "prompt": "Localization compares the laser's scan with what, to estimate the pose?",
     "choices": ["The lab's map", "The sonar ring", "The previous video frame"], "correct": 0,
     "topics": ["laser", "localization"]},
    {"kind": "text", "prompt": "Which skill keeps a set distance to a wall (two words)?",
     "accepted": ["wall following", "wall-following", "wall_following"], "topics": ["wall following"]},
    {"kind": "rating", "prompt": "Driving the robot myself made the sensors easier to understand.",
     "low_label": "Strongly disagree", "high_label": "Strongly agree", "topics": ["sensors"]},
    # The demo lesson "First moves" in three parts, as the 2022 paper's: a comprehension question per part, taken
    # before and after the video, and after it a rating of each part.
    {"kind": "single", "prompt": "A drive command of 0.2 m/s and 0 rad/s makes the robot…",
     "choices": ["Move straight ahead", "Turn on the spot", "Stop"], "correct": 0, "topics": ["part 1: forward"]},
    {"kind": "numeric", "prompt": "Turning on the spot at 0.8 rad/s for 3 s turns the robot by how much?",
     "value": 2.4, "tolerance": 0.1, "unit": "rad", "topics": ["part 2: turn"]},
    {"kind": "single", "prompt": "Go-to-goal needs which parameters?",
     "choices": ["The goal's x and y", "A duration only", "The wheel speeds"], "correct": 0,
     "topics": ["part 3: go to goal"]},
    {"kind": "rating", "prompt": "Part 1 (the robot drove forward with the video) helped me learn.",
     "topics": ["part 1: forward"]},
    {"kind": "rating", "prompt": "Part 2 (the robot turned with the video) helped me learn.",
     "topics": ["part 2: turn"]},
    {"kind": "rating", "prompt": "Part 3 (the robot went to a goal with the video) helped me learn.",
     "topics": ["part 3: go to goal"]},
]
LESSON_BEFORE_QUESTIONS = (7, 8, 9)
LESSON_AFTER_QUESTIONS = (7, 8, 9, 10, 11, 12)
LESSON_BEFORE_TITLE = "Before the lesson: first moves"
LESSON_AFTER_TITLE = "After the lesson: first moves"
# The survey the demo tutor wrote: the 2003 paper's seven statements and one of their own, with its own ends.
DEMO_SURVEY_TITLE = "Evaluate the lab"
DEMO_SURVEY_STATEMENTS = [{"text": text} for _key, text in SURVEY_ITEMS] + [
    {"text": "Seeing the robot move with the lesson's video helped me learn", "low_label": "Not at all",
     "high_label": "A great deal"}]
# The lab survey's answers of the demo classmates: ratings 1-5 in the statements' order, and a comment.
DEMO_SURVEY_ANSWERS: dict[str, tuple[tuple[int, ...], str]] = {
    "demo-classmate-1": ((5, 4, 4, 3, 5, 4, 4, 5), "Driving the robot from home made the odometry lesson concrete."),
    "demo-classmate-2": ((4, 4, 2, 4, 4, 3, 5, 3), "Booking a slot was hard in the week before the test."),
    "demo-classmate-3": ((4, 5, 3, 4, 5, 4, 4, 4), ""),
}
# The experiment's protocol in the demo course (a one-minute learning period, so the journey is walked at once), and
# the classmates' trials on course-A: their details, then seconds per condition (control, 1 s on/off, 3 s on/off),
# near the thesis' figures (the preview saves about a quarter at 3 s).
DEMO_LEARNING_S = 60
DEMO_TRIALS: dict[str, tuple[dict[str, Any], dict[tuple[float, bool], float]]] = {
    "demo-classmate-1": ({"age": 23, "location": "remote", "games_experience": "much", "robots_experience": "none"},
                         {(0.0, False): 41.0, (1.0, True): 47.5, (1.0, False): 55.0, (3.0, True): 61.0,
                          (3.0, False): 82.0}),
    "demo-classmate-2": ({"age": 25, "location": "lab", "games_experience": "some", "robots_experience": "some"},
                         {(0.0, False): 38.5, (1.0, True): 45.0, (1.0, False): 50.5, (3.0, True): 58.0,
                          (3.0, False): 77.5}),
    "demo-classmate-3": ({"age": 24, "location": "remote", "games_experience": "none", "robots_experience": "none"},
                         {(0.0, False): 44.0, (1.0, True): 52.0, (1.0, False): 57.5, (3.0, True): 63.5,
                          (3.0, False): 85.0}),
}
QUIZ_QUESTIONS = (0, 1, 3, 6)  # indices into DEMO_QUESTIONS
TIMED_QUESTIONS = (0, 2, 4, 5)
QUIZ_TITLE = "Practice quiz: sensors and odometry"
TIMED_TITLE = "Timed test: mobile robotics basics"
EXPERIMENTAL_TITLE = "Experimental test: reach the orange tile"

# The demo course in Spanish, beside the English one (docs/languages.md), as a Spanish-speaking tutor writes it: the
# same questions, told in Spanish, with the same kinds, answers and tolerances (so the same grading), in the same
# order (the indices above hold for it); its tests, its survey answered by three Spanish-speaking classmates, and
# the demo student enrolled, so a student reading the lab in Spanish finds every kind of content in Spanish.
DEMO_COURSE_ES_CODE = "DEMO-ROBOTICA"
DEMO_COURSE_ES_TITLE = "Robótica móvil (demo)"
AGREEMENT_ES = {"low_label": "Totalmente en desacuerdo", "high_label": "Totalmente de acuerdo"}
DEMO_QUESTIONS_ES: list[dict[str, Any]] = [
    {"kind": "single", "prompt": "¿Por qué la estimación de la odometría se aleja de la pose real del robot?",
     "choices": ["Las ruedas patinan y las vueltas que miden llevan pequeños errores que se acumulan",
                 "El láser es demasiado lento", "La cámara no está calibrada"], "correct": 0,
     "topics": ["odometría"]},
    {"kind": "numeric", "prompt": "¿Cuántos sonares rodean al robot del laboratorio?", "value": 16, "tolerance": 0,
     "topics": ["sensores", "sonar"]},
    {"kind": "numeric", "prompt": "¿Cuál es el alcance máximo del láser?", "value": 8, "tolerance": 0.5, "unit": "m",
     "topics": ["láser", "sensores"]},
    {"kind": "multiple", "prompt": "¿Qué sensores miden distancias a los obstáculos?",
     "choices": ["Sonar", "Láser", "Codificadores de las ruedas", "Cámara (sola)"], "correct": [0, 1],
     "topics": ["sensores"]},
    {"kind": "single", "prompt": "Para estimar la pose, ¿con qué compara la localización el barrido del láser?",
     "choices": ["Con el mapa del laboratorio", "Con el anillo de sonares", "Con el fotograma anterior del vídeo"],
     "correct": 0, "topics": ["láser", "localización"]},
    {"kind": "text", "prompt": "¿Qué habilidad mantiene una distancia fija a una pared (tres palabras)?",
     "accepted": ["seguimiento de paredes", "seguimiento de pared", "seguir la pared", "wall_following"],
     "topics": ["seguimiento de paredes"]},
    {"kind": "rating", "prompt": "Conducir yo mismo el robot me ayudó a entender los sensores.", **AGREEMENT_ES,
     "topics": ["sensores"]},
    {"kind": "single", "prompt": "Una orden de conducción de 0,2 m/s y 0 rad/s hace que el robot…",
     "choices": ["Avance en línea recta", "Gire sobre sí mismo", "Se pare"], "correct": 0,
     "topics": ["parte 1: adelante"]},
    {"kind": "numeric", "prompt": "Si el robot gira sobre sí mismo a 0,8 rad/s durante 3 s, ¿cuánto gira?",
     "value": 2.4, "tolerance": 0.1, "unit": "rad", "topics": ["parte 2: giro"]},
    {"kind": "single", "prompt": "¿Qué parámetros necesita ir al objetivo?",
     "choices": ["La x y la y del objetivo", "Solo una duración", "Las velocidades de las ruedas"], "correct": 0,
     "topics": ["parte 3: ir al objetivo"]},
    {"kind": "rating", "prompt": "La parte 1 (el robot avanzó con el vídeo) me ayudó a aprender.", **AGREEMENT_ES,
     "topics": ["parte 1: adelante"]},
    {"kind": "rating", "prompt": "La parte 2 (el robot giró con el vídeo) me ayudó a aprender.", **AGREEMENT_ES,
     "topics": ["parte 2: giro"]},
    {"kind": "rating", "prompt": "La parte 3 (el robot fue a un objetivo con el vídeo) me ayudó a aprender.",
     **AGREEMENT_ES, "topics": ["parte 3: ir al objetivo"]},
]
QUIZ_TITLE_ES = "Cuestionario de práctica: sensores y odometría"
TIMED_TITLE_ES = "Prueba cronometrada: fundamentos de robótica móvil"
EXPERIMENTAL_TITLE_ES = "Prueba experimental: llega a la baldosa naranja"
LESSON_BEFORE_TITLE_ES = "Antes de la lección: primeros movimientos"
LESSON_AFTER_TITLE_ES = "Después de la lección: primeros movimientos"
EXPERIMENTAL_INSTRUCTIONS_ES = (f"El objetivo es la baldosa naranja. Toma el control de {DEMO_ROBOT} y llévalo hasta "
                                "allí o usa ir al objetivo. La nota es la distancia real del robot al objetivo.")
DEMO_SURVEY_TITLE_ES = "Evalúa el laboratorio"
DEMO_SURVEY_STATEMENTS_ES = [{"text": text, **AGREEMENT_ES} for text in (
    "Los objetivos de aprendizaje estaban claros", "El curso estaba bien presentado",
    "Era fácil acceder al laboratorio", "Los ejercicios corregidos traían comentarios útiles",
    "El sistema era esencial para el curso", "El sistema era fiable", "El sistema era fácil de usar")] + [
    {"text": "Ver moverse el robot con el vídeo de la lección me ayudó a aprender", "low_label": "Nada",
     "high_label": "Muchísimo"}]
DEMO_SURVEY_ANSWERS_ES: dict[str, tuple[tuple[int, ...], str]] = {
    "demo-companera-1": ((5, 5, 4, 4, 5, 4, 4, 5), "Conducir el robot desde casa me aclaró la lección de odometría."),
    "demo-companero-2": ((4, 3, 3, 4, 4, 4, 5, 4), "Reservar un turno costó en la semana antes de la prueba."),
    "demo-companera-3": ((4, 4, 2, 3, 5, 3, 4, 4), ""),
}


@dataclass(frozen=True)
class DemoCourse:
    """What seeding found or made: the course's id, and the items added (empty when it existed already)."""

    course_id: int | None
    added: list[str]


def seed_demo_course(session: Session, now: datetime | None = None) -> DemoCourse:
    """Creates the demo course and its tests when the course does not exist; the caller commits.

    Needs the demo `tutor` (the course's tutor, and the actor of every service call); without it nothing is
    seeded. The demo `student` is enrolled when the account exists.
    """
    existing = session.scalar(select(Course.id).where(Course.code == DEMO_COURSE_CODE))
    tutor = find_user(session, "tutor")
    if existing is not None:
        return DemoCourse(existing, _survey_classmates(session, tutor, existing))
    if tutor is None or tutor.role != Role.TUTOR:
        return DemoCourse(None, [])
    now = now or datetime.now(UTC)
    course = courses.create_course(session, tutor, DEMO_COURSE_CODE, DEMO_COURSE_TITLE, CourseSettings(
        turn_length_s=DEMO_TURN_LENGTH_S, booking_allowance_min=DEMO_ALLOWANCE_MIN))
    added = [f"course {DEMO_COURSE_TITLE} ({DEMO_ALLOWANCE_MIN} min of bookings a week)"]
    student = find_user(session, "student")
    if student is not None and student.role == Role.STUDENT and student.is_active:
        courses.enrol(session, tutor, course.id, student.username)
        added.append("the demo student enrolled")
    ids = [bank.add_question(session, tutor, course.id, parse_question(q)).id for q in DEMO_QUESTIONS]
    added.append(f"{len(ids)} questions")
    for label, data in _demo_exams(ids, now):
        bank.create_exam(session, tutor, course.id, parse_exam(data))
        added.append(label)
    survey.write_survey(session, tutor, course.id, DEMO_SURVEY_TITLE, parse_statements(DEMO_SURVEY_STATEMENTS))
    added.append(f"the lab survey the tutor wrote ({len(DEMO_SURVEY_STATEMENTS)} statements)")
    added += _survey_classmates(session, tutor, course.id)
    added += seed_demo_plans(session, course.id)
    exercises.ensure_catalogue(session)  # the Python exercises' built-in catalogue
    added.append("the Python exercises' catalogue")
    added += _exercise_test(session, tutor, course.id, now)
    return DemoCourse(course.id, added)


EXAM_WORDS = (QUIZ_TITLE, TIMED_TITLE, EXPERIMENTAL_TITLE, LESSON_BEFORE_TITLE, LESSON_AFTER_TITLE,
              f"The target is the orange tile. Take control of {DEMO_ROBOT} and drive it there or use go-to-goal. "
              "The mark is the robot's true distance to the target.", "navigation")
EXAM_WORDS_ES = (QUIZ_TITLE_ES, TIMED_TITLE_ES, EXPERIMENTAL_TITLE_ES, LESSON_BEFORE_TITLE_ES, LESSON_AFTER_TITLE_ES,
                 EXPERIMENTAL_INSTRUCTIONS_ES, "navegación")


def _demo_exams(ids: list[int], now: datetime,
                words: tuple[str, ...] = EXAM_WORDS) -> list[tuple[str, dict[str, Any]]]:
    """(what the banner calls it, the test as the editor's form sends it): a practice quiz, then a timed test
    and an experimental test open from just before now for OPEN_FOR, then the lesson's tests; their titles, the
    experimental test's instructions and topic in one language (`words`)."""
    quiz_title, timed_title, experimental_title, before_title, after_title, instructions, topic = words
    window = {"opens_at": (now - timedelta(minutes=5)).isoformat(), "closes_at": (now + OPEN_FOR).isoformat()}
    quiz = {"title": quiz_title, "kind": "quiz", "question_ids": [ids[i] for i in QUIZ_QUESTIONS]}
    timed = {"title": timed_title, "kind": "theory", **window, "duration_s": 900, "max_attempts": 3,
             "question_ids": [ids[i] for i in TIMED_QUESTIONS]}
    experimental = {
        "title": experimental_title, "kind": "experimental", **window, "duration_s": 600, "max_attempts": 3,
        "robot_name": DEMO_ROBOT, "task_kind": "reach_point", "x_m": 1.5, "y_m": 1.5, "task_points": 10,
        "task_topics": [topic], "instructions": instructions}
    before = {"title": before_title, "kind": "quiz", "question_ids": [ids[i] for i in LESSON_BEFORE_QUESTIONS]}
    after = {"title": after_title, "kind": "quiz", "question_ids": [ids[i] for i in LESSON_AFTER_QUESTIONS]}
    return [("practice quiz", quiz), ("timed test", timed), (f"experimental test on {DEMO_ROBOT}", experimental),
            ("the lesson's test before", before), ("the lesson's test after", after)]


def seed_spanish_demo_course(session: Session, now: datetime | None = None) -> DemoCourse:
    """The demo course in Spanish ("Robótica móvil (demo)") when it does not exist yet; the caller commits.

    As the English one: the demo `tutor` teaches it, the demo `student` is enrolled, the same questions in Spanish,
    the same five tests, and the tutor's survey in Spanish, answered by three Spanish-speaking classmates (created
    with the course, then disabled) so its charts show. Nothing when the course exists or the demo tutor is gone.
    """
    existing = session.scalar(select(Course.id).where(Course.code == DEMO_COURSE_ES_CODE))
    tutor = find_user(session, "tutor")
    if existing is not None:
        return DemoCourse(existing, [])
    if tutor is None or tutor.role != Role.TUTOR:
        return DemoCourse(None, [])
    now = now or datetime.now(UTC)
    course = courses.create_course(session, tutor, DEMO_COURSE_ES_CODE, DEMO_COURSE_ES_TITLE, CourseSettings(
        turn_length_s=DEMO_TURN_LENGTH_S, booking_allowance_min=DEMO_ALLOWANCE_MIN))
    added = [f"course {DEMO_COURSE_ES_TITLE}"]
    student = find_user(session, "student")
    if student is not None and student.role == Role.STUDENT and student.is_active:
        courses.enrol(session, tutor, course.id, student.username)
        added.append(f"the demo student enrolled in {DEMO_COURSE_ES_TITLE}")
    ids = [bank.add_question(session, tutor, course.id, parse_question(q)).id for q in DEMO_QUESTIONS_ES]
    added.append(f"{len(ids)} questions in Spanish")
    for label, data in _demo_exams(ids, now, EXAM_WORDS_ES):
        bank.create_exam(session, tutor, course.id, parse_exam(data))
        added.append(f"{label} in Spanish")
    statements = survey.write_survey(session, tutor, course.id, DEMO_SURVEY_TITLE_ES,
                                     parse_statements(DEMO_SURVEY_STATEMENTS_ES)).statements
    added.append(f"the lab survey in Spanish ({len(statements)} statements)")
    if not any(find_user(session, name) for name in DEMO_SURVEY_ANSWERS_ES):
        for username, (ratings, comments) in DEMO_SURVEY_ANSWERS_ES.items():
            classmate = create_user(session, username, Role.STUDENT, generate_password())
            courses.enrol(session, tutor, course.id, username)
            survey.submit_survey(session, classmate, course.id, *parse_survey(
                {"ratings": {s.key: rating for s, rating in zip(statements, ratings, strict=True)},
                 "comments": comments}, statements))
            set_active_by_name(session, username, False)
        added.append(f"the Spanish lab survey answered by {len(DEMO_SURVEY_ANSWERS_ES)} demo classmates")
    return DemoCourse(course.id, added)


def _survey_classmates(session: Session, tutor: Any, course_id: int) -> list[str]:
    """Three classmates enrolled, their survey answered, their accounts then disabled; nothing when their accounts
    exist (seeded before, whatever the tutor did with them since) or the demo tutor is gone."""
    if tutor is None or tutor.role != Role.TUTOR or any(find_user(session, name) for name in DEMO_SURVEY_ANSWERS):
        return []
    statements = survey.survey_of(session, course_id).statements  # a course seeded before has the fixed seven
    for username, (ratings, comments) in DEMO_SURVEY_ANSWERS.items():
        classmate = create_user(session, username, Role.STUDENT, generate_password())
        courses.enrol(session, tutor, course_id, username)
        survey.submit_survey(session, classmate, course_id, *parse_survey(
            {"ratings": {s.key: rating for s, rating in zip(statements, ratings, strict=False)},
             "comments": comments}, statements))
        _experiment_trials(session, classmate, course_id)
        set_active_by_name(session, username, False)
    experiment_protocol.set_protocol(session, tutor, course_id, {"learning_s": DEMO_LEARNING_S})
    return [f"the lab survey answered by {len(DEMO_SURVEY_ANSWERS)} demo classmates",
            f"{len(DEMO_TRIALS) * len(experiment_protocol.CONDITIONS_PER_COURSE)} experiment trials of theirs on "
            "course-A"]


# Where each classmate's graded submission of the obstacle-avoidance test ended, round the pillar (1.8, -1.5):
# on the goal (full marks), short of it but within twice its radius (half), and stopped before the pillar (none).
DEMO_EXERCISE = "obstacle-avoidance"
DEMO_EXERCISE_ENDS = {"demo-classmate-1": (3.15, -1.5), "demo-classmate-2": (2.75, -1.0),
                      "demo-classmate-3": (1.3, -1.5)}
ROUND_THE_PILLAR = [(-0.5, -1.5), (1.1, -1.5), (1.8, -0.9), (2.5, -1.2)]


def _exercise_test(session: Session, tutor: Any, course_id: int, now: datetime) -> list[str]:
    """The obstacle-avoidance exercise as a test of the course with its leaderboard open, and a graded submission of
    each demo classmate (a path round the pillar, as a pose log the grader reads), so the ranking shows at once."""
    exercise = exercises.exercise_by_slug(session, DEMO_EXERCISE)
    exercises.attach_to_course(session, tutor, course_id, exercise, now + OPEN_FOR, 10.0)
    leaderboard.set_open(session, tutor, course_id, exercise, True)
    classmates = [(find_user(session, name), end) for name, end in DEMO_EXERCISE_ENDS.items()]
    for hours_ago, (classmate, (end_x, end_y)) in enumerate(classmates, start=1):
        if classmate is None:
            continue
        began = now - timedelta(hours=hours_ago)
        path = [point for point in ROUND_THE_PILLAR if point[0] < end_x] + [(end_x, end_y)]
        trace = [[2.0 * i, x, y, 0.0, x, y, 0.0] for i, (x, y) in enumerate(path)]
        code = exercises.save_code(session, classmate, exercise, exercise.template, began)
        run = exercises.begin_run(session, classmate, exercise, code, "submission", DEMO_ROBOT, exercise.scene,
                                  lambda start: None, _always(began), _always(trace))
        exercises.finish_run(session, classmate, run, None, _always(trace), began + timedelta(seconds=30))
    return [f"the exercise {DEMO_EXERCISE!r} as a test, its leaderboard open, with "
            f"{sum(c is not None for c, _ in classmates)} classmates' graded submissions"]


def _always(value: T) -> Callable[..., T]:
    """A function answering value whatever it is asked (the clock and the pose log of a demo run)."""
    return lambda *_: value


def _experiment_trials(session: Session, classmate: Any, course_id: int) -> None:
    """The classmate's details (with consent) and one trial per condition, in their counterbalanced order."""
    details, seconds = DEMO_TRIALS[classmate.username]
    experiment_protocol.answer_details(session, classmate, {"consent": True, **details})
    experiment_protocol.participant(session, classmate.id).learning_started_at = (  # type: ignore[union-attr]
        datetime.now(UTC) - timedelta(days=1))
    for _ in seconds:
        trial = experiment.assign_trial(session, classmate, "course-a", "course-A", course_id)
        experiment.finish_trial(session, classmate, trial.id,
                                experiment.RunResult(seconds[(trial.delay_s, trial.feedback)], 0))
