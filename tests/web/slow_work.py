"""A stand-in for a long library call (tracking, an export), to stop half-way in the editor's tests."""

import time


def slow_work(stopped):
    """A callable taking the library call's arguments that only reports progress, every 10 ms,
    until the progress callback raises; it appends the exception's class name to ``stopped``."""
    def work(*args, progress, **kwargs):
        try:
            for index in range(3000):
                progress("working", index, 3000)
                time.sleep(0.01)
        except Exception as error:
            stopped.append(type(error).__name__)
            raise
        raise AssertionError("it was never stopped")

    return work
