"""The house rules of ARCHITECTURE.md section 1, checked on the source: the tiers meet only over gRPC."""

from __future__ import annotations

import ast
import pickle
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent


def parse(source: str, filename: str = "<unknown>") -> ast.Module:
    """ast.parse, once more in a fresh interpreter when CPython 3.11's AST constructor reports a recursion depth
    mismatch: a process of the suite that drove Chromium through Playwright's greenlets can trip it (python/cpython
    gh-106905), which says nothing about the source read."""
    try:
        return ast.parse(source, filename)
    except SystemError:
        parsed = subprocess.run(
            [sys.executable, "-c", "import ast, pickle, sys; "
             "sys.stdout.buffer.write(pickle.dumps(ast.parse(sys.stdin.read(), sys.argv[1])))", filename],
            input=source.encode(), capture_output=True, check=True)
        return pickle.loads(parsed.stdout)


def imports_in(path: Path) -> set[str]:
    """The absolute imports of a source file, anywhere in it."""
    names: set[str] = set()
    for node in ast.walk(parse(path.read_text(), str(path))):
        if isinstance(node, ast.Import):
            names.update(alias.name for alias in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module)
    return names


def imported_modules(folder: str) -> dict[str, set[str]]:
    """For each Python file under folder, the top-level-qualified modules it imports."""
    return {str(path.relative_to(ROOT)): imports_in(path) for path in (ROOT / folder).rglob("*.py")}


@pytest.mark.parametrize(
    ("folder", "forbidden"),
    [
        ("middleware", ("skill_server",)),
        ("skill_server", ("middleware",)),
        ("skill_server/sim", ("grpc", "protos", "grpc_health", "grpc_reflection")),
        ("skill_server/skills", ("grpc", "protos", "grpc_health", "grpc_reflection")),
        ("protos", ("middleware", "skill_server")),
    ],
)
def test_folder_does_not_import(folder: str, forbidden: tuple[str, ...]) -> None:
    offenders = {
        file: sorted(n for n in names if n.split(".")[0] in forbidden)
        for file, names in imported_modules(folder).items()
    }
    offenders = {file: names for file, names in offenders.items() if names}
    assert not offenders, f"{folder} must not import {forbidden}: {offenders}"


def test_every_top_level_folder_has_a_readme() -> None:
    for folder in ("client_ui", "middleware", "skill_server", "protos", "migrations", "tests"):
        assert (ROOT / folder / "README.md").is_file(), f"{folder}/README.md is missing"


# The shape of the middleware's robot-facing half (issue 13): one command path, areas that never import upward.

PRODUCT_PACKAGES = ("middleware", "skill_server", "protos")
ROBOT_COMMAND_METHODS = {"drive", "activate_skill", "cancel_goal", "clear_map", "return_to_dock", "set_controller",
                         "reset_evidence_grid", "place_robot",
                         "set_limits", "get_limits", "run_plan", "restart"}
REQUEST_STATE = {("flask", "request"), ("flask", "g"), ("flask", "session"), ("flask_login", "current_user")}


def import_graph(packages: tuple[str, ...] = PRODUCT_PACKAGES) -> dict[str, set[str]]:
    """Each module of packages and the product modules it imports, anywhere in the file (`from a import b`
    counts a.b if that is a module; relative imports resolved), leaving out a module's own packages."""
    files = {".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__"): path
             for pkg in PRODUCT_PACKAGES for path in (ROOT / pkg).rglob("*.py") if "_pb2" not in path.name}

    def resolve(name: str) -> str | None:
        while name and name not in files:
            name = name.rpartition(".")[0]
        return name if name not in PRODUCT_PACKAGES else None

    graph: dict[str, set[str]] = {}
    for module, path in files.items():
        if not module.startswith(packages):
            continue
        package = module if path.name == "__init__.py" else module.rpartition(".")[0]
        targets: list[str] = []
        for node in ast.walk(parse(path.read_text(), str(path))):
            if isinstance(node, ast.Import):
                targets += [alias.name for alias in node.names]
            elif isinstance(node, ast.ImportFrom):
                base = node.module or ""
                if node.level:
                    parts = package.split(".")[: len(package.split(".")) - (node.level - 1)]
                    base = ".".join(parts + ([base] if base else []))
                targets += [base] + [f"{base}.{alias.name}" for alias in node.names]
        resolved = {resolve(target) for target in targets}
        graph[module] = {r for r in resolved if r and r != module and not module.startswith(r + ".")}
    return graph


def import_circles(graph: dict[str, set[str]]) -> list[list[str]]:
    """The strongly connected components of more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    circles: list[list[str]] = []

    def visit(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        for other in graph.get(node, ()):
            if other not in index:
                visit(other)
                low[node] = min(low[node], low[other])
            elif other in stack:
                low[node] = min(low[node], index[other])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                circles.append(sorted(component))

    for node in graph:
        if node not in index:
            visit(node)
    return circles


def test_no_import_circles_anywhere_in_the_product() -> None:
    assert import_circles(import_graph()) == []


def test_the_circle_check_finds_a_circle() -> None:
    assert import_circles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]


@pytest.mark.parametrize(
    ("folder", "forbidden"),
    [
        ("middleware/access", ("middleware.bookings", "middleware.teaching", "middleware.lab")),
        ("middleware/robots", ("middleware.access", "middleware.teaching", "middleware.lab", "flask_login")),
        ("middleware/farm", ("middleware.access", "middleware.teaching", "middleware.lab", "middleware.accounts",
                             "flask_login")),
    ],
)
def test_lower_middleware_layers_do_not_import_upward(folder: str, forbidden: tuple[str, ...]) -> None:
    offenders = {
        file: upward for file, names in imported_modules(folder).items()
        if (upward := sorted(n for n in names if any(n == f or n.startswith(f + ".") for f in forbidden)))
    }
    assert not offenders, f"{folder} imports upward: {offenders}"


# Plumbing every area stands on; it knows no feature (a feature's hook is handed to it by create_app).
PLUMBING = ("middleware.realtime", "middleware.live", "middleware.robots", "middleware.db", "middleware.errors",
            "middleware.events", "middleware.locking", "middleware.validation", "middleware.web", "middleware.i18n")
# The areas; middleware.auth is not one of them for plumbing: the sockets' login check reads its login records.
FEATURE_AREAS = ("access", "accounts", "assessment", "bookings", "chat", "courses", "experiment", "farm", "lab",
                 "plans", "preferences", "teaching", "lti", "recordings", "exercises", "analytics", "api")


def area_of(module: str) -> str:
    """middleware.lab.skills -> lab; middleware.realtime -> realtime; the package itself -> middleware."""
    parts = module.split(".")
    return parts[1] if len(parts) > 1 else parts[0]


def test_plumbing_imports_no_feature() -> None:
    offenders = {module: sorted(t for t in targets if area_of(t) in FEATURE_AREAS)
                 for module, targets in import_graph(("middleware",)).items() if module.startswith(PLUMBING)}
    offenders = {module: targets for module, targets in offenders.items() if targets}
    assert not offenders, f"plumbing knows no feature; create_app hands it the hooks it needs: {offenders}"


def mutual_area_imports(graph: dict[str, set[str]]) -> list[tuple[str, str]]:
    """Pairs of middleware areas that import each other, anywhere in a file (a function-level import counts)."""
    edges = {(area_of(m), area_of(t)) for m, targets in graph.items() for t in targets
             if m.startswith("middleware.") and t.startswith("middleware.") and area_of(m) != area_of(t)}
    return sorted((a, b) for a, b in edges if a < b and (b, a) in edges)


def test_no_two_middleware_areas_import_each_other() -> None:
    assert mutual_area_imports(import_graph(("middleware",))) == [], (
        "one of the two areas is the lower floor: move the shared rule down, or hand a hook through create_app")


def test_the_mutual_import_check_finds_a_pair_through_a_function_level_import() -> None:
    graph = {"middleware.lab.skills": {"middleware.plans.services"}, "middleware.plans.routes": {"middleware.lab.x"},
             "middleware.courses.routes": {"middleware.accounts.web"}}
    assert mutual_area_imports(graph) == [("lab", "plans")]


# Modules that import inside functions, and why: a start-up cost or an optional dependency. Nowhere else: an import
# inside a function hides an import circle from the checks above.
FUNCTION_LEVEL_IMPORTS_ALLOW_LIST = {
    "middleware/cli.py": "a command imports only what it runs: `telelab --help` starts without the app",
    "middleware/__init__.py": "the app is imported on first use of create_app: a writer child or a Ray actor that "
                              "imports one module of the package does not import every area with it",
    "middleware/lab_runner.py": "`telelab up` imports the app, the farm owner and gunicorn only when it starts them",
    "middleware/serve.py": "gunicorn and the app are imported where they serve, not by the command configuring them",
    "middleware/farm/setup.py": "only the farm backend TELELAB_FARM names is imported",
    "middleware/farm/ray_farm.py": "ray is optional and slow to import: only a lab using the Ray farm imports it",
    "middleware/events.py": "psycopg is needed only with PostgreSQL",
    "middleware/db.py": "alembic (0.3 s) only where a database is migrated: a worker or writer child never imports it",
}


def function_level_imports(source: str) -> list[int]:
    """Lines of the imports made inside a function of source."""
    return sorted({node.lineno for function in ast.walk(parse(source))
                   if isinstance(function, ast.FunctionDef | ast.AsyncFunctionDef)
                   for node in ast.walk(function) if isinstance(node, ast.Import | ast.ImportFrom)})


def test_imports_are_at_module_level_unless_a_start_up_cost_needs_them() -> None:
    offenders = [f"{path.relative_to(ROOT)}:{line}" for path in sorted((ROOT / "middleware").rglob("*.py"))
                 if str(path.relative_to(ROOT)) not in FUNCTION_LEVEL_IMPORTS_ALLOW_LIST
                 for line in function_level_imports(path.read_text())]
    assert not offenders, f"import at module level (or name the start-up cost with the module): {offenders}"


def test_only_the_launcher_command_imports_the_launcher() -> None:
    importers = {file for file, names in imported_modules("middleware").items() if "middleware.lab_runner" in names}
    assert importers <= {"middleware/cli.py"}, f"the launcher only composes; imported by {sorted(importers)}"


def robot_command_calls(source: str) -> list[str]:
    """The RobotLink command methods called in source: link.drive(...), self.link.set_controller(...),
    registry.get(name).activate_skill(...). A link is always named "link" in the middleware, so a receiver
    whose text mentions it (or one that is itself a call's result) is a link; the command path's own
    Commander.drive(...) on a "robot" is not."""
    calls = []
    for node in ast.walk(parse(source)):
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                and node.func.attr in ROBOT_COMMAND_METHODS):
            receiver = node.func.value
            if isinstance(receiver, ast.Call) or "link" in ast.unparse(receiver).lower():
                calls.append(f"{ast.unparse(node.func)} (line {node.lineno})")
    return calls


def test_only_the_command_path_sends_robot_commands() -> None:
    callers = {str(p.relative_to(ROOT)): calls for p in (ROOT / "middleware").rglob("*.py")
               if (calls := robot_command_calls(p.read_text()))}
    assert set(callers) <= {"middleware/access/commands.py"}, (
        f"every robot command goes through middleware/access/commands.py; also sent from {callers}")


def test_the_command_call_check_tells_links_from_the_command_path() -> None:
    source = ("link.drive(t, 1, 0, 0)\nself.link.set_controller(t)\nregistry.get(n).cancel_goal(t, g)\n"
              "robot.drive(1, 0.0, 0.0)\ncoordinator.join(n, u)\n")
    assert [c.split(" ")[0] for c in robot_command_calls(source)] == [
        "link.drive", "self.link.set_controller", "registry.get(n).cancel_goal"]


def test_services_never_read_the_request() -> None:
    service_files = [p for p in (ROOT / "middleware").rglob("*.py")
                     if p.name in {"services.py", "round_robin.py", "commands.py", "coordinator.py"}
                     or p.parent.name == "robots"
                     or p.name in {"lessons.py", "tours.py", "cues.py", "command_form.py", "practice_robots.py"}]
    offenders = {}
    for path in service_files:
        for node in ast.walk(parse(path.read_text(), str(path))):
            if isinstance(node, ast.ImportFrom) and node.module:
                names = {(node.module, alias.name) for alias in node.names} & REQUEST_STATE
                if names:
                    offenders[str(path.relative_to(ROOT))] = sorted(n for _, n in names)
    assert not offenders, f"services take what they need as arguments, never from the request: {offenders}"


# The skill server's layers (issue 13): sim/ at the bottom, the Robot facade between core and adapter.

SKILL_SERVER_VALUE_MODULES = ("skill_server.errors", "skill_server.goals", "skill_server.schema")


def test_skill_server_sim_imports_nothing_from_the_layers_above_it() -> None:
    above = ("skill_server.skills", "skill_server.sequencer", "skill_server.robot", "skill_server.service",
             "skill_server.server")
    offenders = {module: sorted(i for i in imported if i.startswith(above))
                 for module, imported in import_graph(("skill_server.sim",)).items()}
    offenders = {module: names for module, names in offenders.items() if names}
    assert not offenders, f"skill_server/sim must not import skills/ or anything built on them: {offenders}"


def test_the_servicer_reaches_the_robot_core_only_through_the_facade() -> None:
    allowed = ("skill_server.robot", "skill_server.service", "protos", *SKILL_SERVER_VALUE_MODULES)
    offenders = {module: sorted(i for i in imported if not i.startswith(allowed))
                 for module, imported in import_graph(("skill_server.service",)).items()}
    offenders = {module: names for module, names in offenders.items() if names}
    assert not offenders, f"the servicer imports the robot core only through skill_server.robot: {offenders}"
    internals = {"world", "sequencer", "perception", "track_monitor"}
    reached = sorted(
        f"{path.relative_to(ROOT)}:{node.lineno} .{node.attr}"
        for path in (ROOT / "skill_server" / "service").rglob("*.py")
        for node in ast.walk(parse(path.read_text(), str(path)))
        if isinstance(node, ast.Attribute) and node.attr in internals
    )
    assert not reached, f"the servicer calls the Robot facade, never the world or sequencer behind it: {reached}"


# --- one unit of work, one Refused family (middleware/db.py, middleware/errors.py) --------------------------

# "path::function": why that view must commit or roll back itself. Empty: middleware/db.py's after_commit()
# covers "commit before something irreversible outside the database"; add an entry only with its reason.
ROUTE_TRANSACTION_ALLOW_LIST: dict[str, str] = {}
# Exception classes with a stable code that are not a Refused, and why.
CODED_EXCEPTIONS_ALLOW_LIST: dict[str, str] = {}
ROBOT_ERRORS = {"CommandRefused", "RobotUnavailable"}
# Modules that may raise their own refusal in place of a robot's, and why (a sentence the robot's cannot say).
ROBOT_ERROR_REWORDING_ALLOW_LIST = {
    "middleware/assessment/obstacle_zone.py": "saving an obstacle-zone test: it is graded against the robot's "
                                              "scene, so the tutor is told to start the robot, naming robot_name",
}


def declares_views(source: str) -> bool:
    """Whether source makes a Blueprint or declares a WebSocket channel (sock.route(...)), whatever its name."""
    for node in ast.walk(parse(source)):
        if isinstance(node, ast.Call):
            called = node.func.attr if isinstance(node.func, ast.Attribute) else getattr(node.func, "id", "")
            if called == "Blueprint" or (called == "route" and ast.unparse(node.func) == "sock.route"):
                return True
    return False


def is_route_file(path: Path) -> bool:
    """Routes, pages and sockets: the files whose views the request's unit of work wraps."""
    return (path.name in {"routes.py", "pages.py", "sockets.py"} or path.name.endswith("_routes.py")
            or declares_views(path.read_text()))


def test_the_route_file_check_finds_blueprints_whatever_their_name() -> None:
    names = {str(p.relative_to(ROOT)) for p in (ROOT / "middleware").rglob("*.py") if is_route_file(p)}
    assert {"middleware/lab/skills.py", "middleware/teaching/tour_live.py", "middleware/lab/routes.py"} <= names
    assert "middleware/access/commands.py" not in names


def robot_error_translations(source: str) -> list[int]:
    """Lines of every `except` that catches a robot error (CommandRefused, RobotUnavailable) only to raise
    another error in its place: those are Refused already, and the one handler renders them."""
    lines = []
    for node in ast.walk(parse(source)):
        if not isinstance(node, ast.ExceptHandler) or node.type is None:
            continue
        caught = {n.id if isinstance(n, ast.Name) else n.attr for n in ast.walk(node.type)
                  if isinstance(n, ast.Name | ast.Attribute)}
        if caught & ROBOT_ERRORS and all(isinstance(s, ast.Raise) and s.exc is not None for s in node.body):
            lines.append(node.lineno)
    return lines


def test_no_middleware_module_catches_a_robot_error_only_to_raise_another() -> None:
    offenders = [f"{path.relative_to(ROOT)}:{line}" for path in sorted((ROOT / "middleware").rglob("*.py"))
                 if str(path.relative_to(ROOT)) not in ROBOT_ERROR_REWORDING_ALLOW_LIST
                 for line in robot_error_translations(path.read_text())]
    assert not offenders, ("a robot's refusal or absence is a Refused (middleware/robots/refusals.py): let it pass "
                           f"to the one handler instead of translating it: {offenders}")


def test_the_translation_check_tells_a_translation_from_a_decision() -> None:
    source = ("try:\n    a()\nexcept (CommandRefused, RobotUnavailable) as e:\n    raise refusal_error(e) from None\n"
              "try:\n    a()\nexcept link.RobotUnavailable as e:\n    raise ApiError(503, 'x', str(e))\n"
              "try:\n    a()\nexcept RobotUnavailable:\n    info = None\n"
              "try:\n    a()\nexcept CommandRefused as e:\n    if e.reason != 'x':\n        raise\n    b()\n")
    assert robot_error_translations(source) == [3, 7]


def transaction_calls(source: str) -> list[tuple[str, str, int]]:
    """(enclosing function, method, line) of every .commit() or .rollback() call in source."""
    calls = []

    def visit(node: ast.AST, function: str) -> None:
        for child in ast.iter_child_nodes(node):
            name = child.name if isinstance(child, ast.FunctionDef | ast.AsyncFunctionDef) else function
            if (isinstance(child, ast.Call) and isinstance(child.func, ast.Attribute)
                    and child.func.attr in {"commit", "rollback"}):
                calls.append((function, child.func.attr, child.lineno))
            visit(child, name)

    visit(parse(source), "<module>")
    return calls


def test_routes_leave_commit_and_rollback_to_the_unit_of_work() -> None:
    offenders = [f"{path.relative_to(ROOT)}:{line} {function}() calls .{method}()"
                 for path in sorted((ROOT / "middleware").rglob("*.py")) if is_route_file(path)
                 for function, method, line in transaction_calls(path.read_text())
                 if f"{path.relative_to(ROOT)}::{function}" not in ROUTE_TRANSACTION_ALLOW_LIST]
    assert not offenders, ("the request's unit of work commits and rolls back (middleware/db.py); use after_commit() "
                           f"for what must follow the commit, or allow-list the view with a reason: {offenders}")


# Modules ("path") or functions ("path::function") that commit or roll back sessions of their own, and why; the
# request's (and a socket's) unit of work is middleware/db.py's alone. A service takes the caller's session and flushes.
OWN_TRANSACTIONS_ALLOW_LIST = {
    "middleware/db.py": "the unit of work's owner",
    "middleware/cli.py": "console commands: each is a unit of work of its own",
    "middleware/lab_runner.py": "`telelab up` seeds the lab before any request",
    "middleware/teaching/demo_content.py": "`telelab up` seeds the demo content before any request",
    "middleware/robots/catalog.py": "the registry seeds the configured robots at start, racing other workers",
    "middleware/auth/session_records.py": "a login's last_seen_at, committed at once before the request writes",
    "middleware/teaching/class_sessions.py::_set_seat": "the background start of a class's robots records each "
                                                        "seat's outcome",
}


def test_only_the_unit_of_work_and_named_duties_commit_or_roll_back() -> None:
    offenders = sorted(f"{path.relative_to(ROOT)}:{line} {function}() calls .{method}()"
                       for path in (ROOT / "middleware").rglob("*.py")
                       if str(path.relative_to(ROOT)) not in OWN_TRANSACTIONS_ALLOW_LIST
                       for function, method, line in transaction_calls(path.read_text())
                       if f"{path.relative_to(ROOT)}::{function}" not in OWN_TRANSACTIONS_ALLOW_LIST)
    assert not offenders, ("nothing commits or rolls back a caller's session behind its back: services flush and "
                           "raise a Refused, the unit of work's owner ends it (a background duty uses "
                           f"unit_of_work(app) or `with sessions() as s, s.begin()`): {offenders}")


def coded_exception_classes() -> list[str]:
    """module.Class of every class in middleware that sets a `code` attribute (self.code = ..., or in its body)."""
    found = []
    for path in (ROOT / "middleware").rglob("*.py"):
        module = ".".join(path.relative_to(ROOT).with_suffix("").parts).removesuffix(".__init__")
        for node in ast.walk(parse(path.read_text(), str(path))):
            if not isinstance(node, ast.ClassDef):
                continue
            targets = [t for n in ast.walk(node) if isinstance(n, ast.Assign | ast.AnnAssign)
                       for t in (n.targets if isinstance(n, ast.Assign) else [n.target])]
            names = {e.attr if isinstance(e, ast.Attribute) else e.id for t in targets
                     for e in (t.elts if isinstance(t, ast.Tuple) else [t]) if isinstance(e, ast.Attribute | ast.Name)}
            if "code" in names:
                found.append(f"{module}.{node.name}")
    return found


def test_every_coded_exception_in_the_middleware_is_a_refused() -> None:
    import importlib

    from middleware.errors import Refused

    outsiders = []
    for qualified in coded_exception_classes():
        module, name = qualified.rsplit(".", 1)
        cls = getattr(importlib.import_module(module), name)
        if (isinstance(cls, type) and issubclass(cls, BaseException) and not issubclass(cls, Refused)
                and qualified not in CODED_EXCEPTIONS_ALLOW_LIST):
            outsiders.append(qualified)
    assert "middleware.errors.Refused" in coded_exception_classes()
    assert not outsiders, ("an error with a stable code subclasses middleware.errors.Refused (status, code, message, "
                           f"field) so the one handler renders it: {outsiders}")


STATIC = ROOT / "client_ui" / "static"
# import ... from "x", import "x", export ... from "x", import("x"): each module an ES module names, as written.
JS_IMPORT = re.compile(r"""(?:\bimport\s*(?:[\w*${}\s,]+?\s*from\s*)?|\bexport\s*[\w*${}\s,]+?\s*from\s*"""
                       r"""|\bimport\s*\(\s*)["']([^"']+)["']""")


def js_imports(path: Path, text: str | None = None) -> set[Path]:
    """The static files an ES module under client_ui/static imports (relative or /static/ paths), resolved."""
    found = set()
    for name in JS_IMPORT.findall(path.read_text(encoding="utf-8") if text is None else text):
        if name.startswith("/static/"):
            found.add((STATIC / name.removeprefix("/static/")).resolve())
        elif name.startswith("."):
            found.add((path.parent / name).resolve())
    return found


def cross_page_imports(modules: dict[Path, set[Path]]) -> list[str]:
    """A page's module importing another page's, or a shared module (lib/, panels/) importing any page's."""
    pages = (STATIC / "pages").resolve()
    found = []
    for module, targets in sorted(modules.items()):
        own = module.relative_to(pages).parts[0] if module.is_relative_to(pages) else None
        for target in sorted(targets):
            if target.is_relative_to(pages) and target.relative_to(pages).parts[0] != own:
                found.append(f"{module.relative_to(STATIC)} imports {target.relative_to(STATIC)}")
    return found


def test_no_page_imports_another_page() -> None:
    modules = {path.resolve(): js_imports(path) for path in STATIC.rglob("*.js") if "vendor" not in path.parts}
    assert not cross_page_imports(modules), (
        "what two pages share lives in static/lib/ (the console's in lib/console/), never in one page's folder: "
        f"{cross_page_imports(modules)}")


def test_the_cross_page_check_finds_a_page_or_a_library_importing_a_page() -> None:
    pages = STATIC / "pages"
    teaching = (pages / "teaching" / "tour.js").resolve()
    shared = (STATIC / "lib" / "console" / "wiring.js").resolve()
    text = ('import { a } from "../lab/console.js";\nimport "./own.js";\n'
            'const b = await import("/static/pages/lab/x.js");')
    assert js_imports(teaching, text) == {(pages / "lab" / "console.js").resolve(),
                                          (pages / "teaching" / "own.js").resolve(), (pages / "lab" / "x.js").resolve()}
    found = cross_page_imports({teaching: js_imports(teaching, text),
                                shared: {(pages / "lab" / "console.js").resolve()}})
    assert found == ["lib/console/wiring.js imports pages/lab/console.js",
                     "pages/teaching/tour.js imports pages/lab/console.js",
                     "pages/teaching/tour.js imports pages/lab/x.js"]


# The practice manager's methods that work in units of work of their own (background duties, the CLI): a view calls
# them only in what it hands to after_commit, never in its body (it claims or removes the row in its own session).
OWN_UNIT_PRACTICE_METHODS = {"start", "stop", "stop_named", "shutdown"}


def own_unit_calls_in_views(source: str) -> list[int]:
    """Lines where a function's own body (not a nested def or lambda, which after_commit may run) calls one of
    OWN_UNIT_PRACTICE_METHODS on practice_manager(...) or on a name it assigned from it."""
    lines = []

    def body_nodes(function: ast.AST):
        pending = list(ast.iter_child_nodes(function))
        while pending:
            node = pending.pop()
            if not isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef | ast.Lambda):
                yield node
                pending.extend(ast.iter_child_nodes(node))

    def from_manager(node: ast.AST) -> bool:
        return isinstance(node, ast.Call) and getattr(node.func, "id", "") == "practice_manager"

    for function in ast.walk(parse(source)):
        if not isinstance(function, ast.FunctionDef | ast.AsyncFunctionDef):
            continue
        nodes = list(body_nodes(function))
        managers = set()
        for node in nodes:
            if isinstance(node, ast.Assign):
                pairs = [(t, node.value) for t in node.targets]
                for target, value in list(pairs):
                    if isinstance(target, ast.Tuple) and isinstance(value, ast.Tuple):
                        pairs.extend(zip(target.elts, value.elts, strict=False))
                managers |= {t.id for t, v in pairs if isinstance(t, ast.Name) and from_manager(v)}
        for node in nodes:
            if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)
                    and node.func.attr in OWN_UNIT_PRACTICE_METHODS
                    and (from_manager(node.func.value) or getattr(node.func.value, "id", None) in managers)):
                lines.append(node.lineno)
    return sorted(lines)


def test_views_start_and_stop_practice_robots_only_after_the_commit() -> None:
    offenders = [f"{path.relative_to(ROOT)}:{line}" for path in sorted((ROOT / "middleware").rglob("*.py"))
                 if is_route_file(path) for line in own_unit_calls_in_views(path.read_text())]
    assert not offenders, ("a view claims a practice robot (begin_start) or removes it (begin_stop) in the request's "
                           "session and hands the farm's part to after_commit; start()/stop() commit sessions of "
                           f"their own, for background duties: {offenders}")


def test_the_practice_check_tells_a_view_s_own_call_from_an_after_commit_callback() -> None:
    source = ("def start():\n    manager = practice_manager()\n    robot = manager.start(1, 'ann')\n"
              "def end():\n    owners, manager = ends(), practice_manager()\n\n"
              "    def stop_robots():\n        for owner in owners:\n            manager.stop(owner)\n\n"
              "    after_commit(stop_robots)\n    after_commit(lambda: manager.finish_stop('x'))\n"
              "def admin():\n    practice_manager().stop_named('practice-ann')\n    other.stop()\n")
    assert own_unit_calls_in_views(source) == [3, 14]


CONSOLE = STATIC / "lib" / "console"
REGISTERS_SERVICE = re.compile(r"\bregisterFeedService\s*\(")


def console_wiring_problems(modules: dict[str, str]) -> list[str]:
    """The console's wiring is composition: console-wiring.js registers no feed service (each lives in a module of
    its own, as panels do), and no feed service module imports it (a service meets the wiring as connect's argument
    and talks to the others through its events)."""
    problems = []
    for name, text in sorted(modules.items()):
        registers = bool(REGISTERS_SERVICE.search(text))
        if name == "console-wiring.js" and registers:
            problems.append("console-wiring.js registers a feed service")
        if name != "console-wiring.js" and registers and re.search(r"""from\s*["']\./console-wiring\.js["']""", text):
            problems.append(f"{name} registers a feed service and imports console-wiring.js")
    return problems


def test_the_console_s_feed_services_live_in_modules_of_their_own() -> None:
    modules = {path.name: path.read_text(encoding="utf-8") for path in CONSOLE.glob("*.js")}
    assert not console_wiring_problems(modules), console_wiring_problems(modules)
    services = [name for name, text in modules.items() if REGISTERS_SERVICE.search(text) and name != "feed-services.js"]
    imported = {path.name for path in js_imports(CONSOLE / "console-wiring.js")}
    assert set(services) <= imported, f"console-wiring.js imports every service module: {set(services) - imported}"


def test_the_console_check_finds_a_service_registered_in_the_wiring() -> None:
    assert console_wiring_problems({
        "console-wiring.js": 'import "./drive-service.js";\nstatic { registerFeedService("map", () => {}); }',
        "drive-service.js": 'import { ConsoleWiring } from "./console-wiring.js";\nregisterFeedService("drive", f);',
        "queue-service.js": 'registerFeedService("queue", connectQueue);',
    }) == ["console-wiring.js registers a feed service", "drive-service.js registers a feed service and imports "
                                                          "console-wiring.js"]
