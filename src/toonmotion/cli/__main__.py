"""``python -m toonmotion.cli``: the same as the ``toonmotion`` command."""

from toonmotion.cli import main

main()
