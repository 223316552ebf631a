"""Courses: tutors create them, enrol students (one by one or from a CSV file) and set their limits."""
