"""The progress callback every long-running library call accepts.

``progress(stage, index, count)`` is called as work goes on: ``stage`` names what is being done
(``"mesh"``, ``"tracking"``, ``"rendering"``), ``index`` counts the steps of that stage done so
far and ``count`` is how many there are. The library never prints; front ends turn these calls
into a progress bar (the CLI) or messages to the page (the editor).

>>> seen = []
>>> report: Progress = lambda stage, index, count: seen.append((stage, index, count))
>>> report("tracking", 1, 10); seen
[('tracking', 1, 10)]
"""

from collections.abc import Callable

Progress = Callable[[str, int, int], None]
