"""The capture client of live sessions (``python -m capture``, also ``python -m analysis stream``;
README, "Command line"): frame sources (a BVH file paced in real time, a TCP stream of frame
lines), the WebSocket client that streams to the server's live session, and the in-process run
against `analysis.live`.

Network I/O lives here, above the numerical core: `analysis` never imports sockets, WebSockets
or HTTP clients. The command line's ``stream`` subcommand hands over to `capture.stream`.
"""
