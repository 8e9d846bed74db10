"""Harnesses that measure toonmotion on data with a known answer, shared by the tests and the
benchmarks (``benchmarks/``). They sit above ``io/`` and ``capture/``; nothing else in the
library imports them.

- :mod:`toonmotion.testing.mocap_tracking`: real motion capture rendered as a textured figure,
  tracked from the true joint rectangles, and scored against the true joints.
"""
