"""The deformed vertices' wire form: float32 exactly, in order, and smaller than JSON numbers."""

import json

import numpy as np

from toonmotion import api
from toonmotion.samples import sample_character
from toonmotion.web.wire import decode_vertices, encode_vertices


def test_vertices_come_back_as_their_float32_values_in_order():
    U = np.random.default_rng(3).uniform(-2000, 2000, size=(1501, 2))
    back = decode_vertices(encode_vertices(U))
    assert back.shape == U.shape
    np.testing.assert_array_equal(back, U.astype(np.float32))  # x, y of each vertex, row by row
    assert np.abs(back - U).max() <= 2000 * 2.0**-24  # half a float32 step at the largest coordinate


def test_a_character_mesh_is_smaller_on_the_wire_than_as_json_numbers():
    rgba, skeleton = sample_character()
    V = api.rig_image(rgba, skeleton=skeleton).mesh.V
    text = encode_vertices(V)
    assert text.isascii() and json.loads(json.dumps(text)) == text
    assert len(text) < len(json.dumps(np.round(V, 3).ravel().tolist()))
    np.testing.assert_array_equal(decode_vertices(text), V.astype(np.float32))
