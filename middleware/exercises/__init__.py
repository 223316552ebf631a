"""Programming exercises: the student's Python runs in their browser on Pyodide, the server grades from the truth."""
