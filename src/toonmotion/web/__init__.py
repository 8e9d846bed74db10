"""The toonmotion editor: a local web server over the library API, and its browser front end.

:mod:`~toonmotion.web.server` serves the page (``static/``), the project's data and a WebSocket
for live posing; it calls :mod:`toonmotion.api` like the CLI does. Start it with
``toonmotion edit PROJECT``.
"""
