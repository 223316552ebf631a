"""Assessment: question bank, quizzes, timed theoretical and experimental tests, the corrector, the survey."""
