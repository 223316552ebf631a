"""The close codes of the channels (client_ui/static/lib/transport.js knows the final ones)."""

# The client does not reconnect after these.
CLOSE_NOT_LOGGED_IN = 4401
CLOSE_FORBIDDEN = 4403
CLOSE_NOT_FOUND = 4404
# It reconnects, with its backoff, after these.
CLOSE_TRY_AGAIN_LATER = 1013
CLOSE_GOING_AWAY = 1001
CLOSE_SERVICE_RESTART = 1012  # this worker is leaving (a rolling restart): the client reconnects to another
# A channel whose handler failed (RFC 6455's "internal error"); on a link, that channel alone.
CLOSE_SERVER_FAILED = 1011
# A client over its inbound limits (RFC 6455's "policy violation").
CLOSE_TOO_MANY_MESSAGES = 1008
