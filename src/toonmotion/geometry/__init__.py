"""Pure array maths on points, polygons and segments. Imports nothing else of toonmotion."""
