"""Gunicorn's configuration for Telelab's web workers: `telelab up` reads this file (adding the bind address and the
worker count), and a web host of a deployment runs

    gunicorn -c deploy/gunicorn.conf.py -b 127.0.0.1:5000 -w 4 'middleware:create_app()'

SIGHUP to the master restarts the workers one at a time: a new worker first makes its app, and only then does an old
one leave; a leaving worker answers the messages its sockets have read, closes them with 1012 (the page reconnects
to another worker) and finishes its requests, within graceful_timeout.
"""

from middleware.serve import GRACEFUL_TIMEOUT_S, leave_worker, prepare_master, settle_worker

worker_class = "gthread"
threads = 200  # an open WebSocket holds no thread (middleware/live/loop.py); these serve HTTP requests
graceful_timeout = GRACEFUL_TIMEOUT_S
timeout = 60
keepalive = 5
loglevel = "warning"
proc_name = "telelab"

on_starting = prepare_master  # checks the PostgreSQL connection budget, then restarts workers one at a time
post_worker_init = settle_worker
worker_exit = leave_worker
