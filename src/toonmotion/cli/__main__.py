"""``python -m toonmotion.cli``: the same as the ``toonmotion`` command."""

from toonmotion.cli import main

if __name__ == "__main__":  # run as a module, not imported (the docs' API reference imports it)
    main()
