"""A pool's robots are stopped in the request's unit of work: their rows go with the request's commit and the farm
stops the robots after it, so a request rolled back stops nothing, and no keeper starts again a robot stopped
before its row went (the order was the other way round); the admin's form and the console command both work."""

from __future__ import annotations

from tests.integration.teaching.test_farm_admin import _client
from tests.integration.teaching.test_pool_admin import _pool_rows


def test_a_pool_stopped_in_a_rolled_back_unit_of_work_keeps_running_and_the_admin_s_form_stops_it(
        live_server) -> None:
    from middleware.db import session_factory
    from middleware.farm.pool_robots import keep_pool_robots, remove_pool_rows, start_pool_robots
    from middleware.farm.setup import robot_farm

    app = live_server.app
    farm, sessions = robot_farm(app), session_factory(app)
    admin = _client(live_server, "root", "admin")
    try:
        with sessions() as session, session.begin():
            started = start_pool_robots(farm, session, "uow", "lab", 2)
        with sessions() as session:
            assert remove_pool_rows(session, "uow") == started
            assert sorted(robot.name for robot in farm.robots()) == started  # nothing stops before the commit
            session.rollback()
        assert sorted(_pool_rows(app)) == started and keep_pool_robots(farm, sessions) == []

        token = admin.csrf_token("/admin/pools")
        status, _headers, _page = admin.request("POST", "/admin/pools/uow/stop", {"csrf_token": token})
        assert status == 303
        assert _pool_rows(app) == {} and farm.robots() == []
        assert keep_pool_robots(farm, sessions) == [] and farm.robots() == []  # nothing to start again
        status, _headers, page = admin.request("GET", "/admin/pools")
        assert status == 200 and "Stopped 2 robot(s) of uow." in page
    finally:
        for robot in farm.robots():
            farm.stop(robot.name)
