"""The API described: each JSON route's contract (contract.py), the OpenAPI document made from them
(document.py), the WebSocket channels (channels.py) and the routes that serve them (routes.py)."""
