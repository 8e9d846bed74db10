"""The job file's schema: bad keys and missing files are one-line errors naming them."""

import pytest

from toonmotion.errors import BatchError
from toonmotion.io.batch_job import load_job

HEAD = """
[[character]]
name = "hero"
drawing = "hero.png"
[[motion]]
name = "wave"
keys = "keys.json"
"""
OUTPUT = """
[output]
formats = ["gif", "glb"]
"""


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "hero.png").write_bytes(b"not checked until rigged")
    (tmp_path / "keys.json").write_text("{}")
    return tmp_path


def _load(folder, text):
    (folder / "job.toml").write_text(text)
    return load_job(folder / "job.toml")


def test_a_good_job_resolves_paths_and_takes_every_pair(folder):
    job = _load(folder, HEAD + OUTPUT + '[[motion]]\nname = "run"\nkeys = "keys.json"\n')
    assert job.pairs == (("hero", "wave"), ("hero", "run"))
    assert job.characters[0].drawing == str(folder / "hero.png")
    assert job.outputs[0].formats == ["gif", "glb"]


@pytest.mark.parametrize(("text", "match"), [
    ("colour = 3\n" + HEAD + OUTPUT, r"job.toml: colour: Extra inputs"),
    (HEAD.replace("drawing", "drawng") + OUTPUT, r"character\[0\]"),
    (HEAD + '[output]\nformats = ["gif", "avi"]\n', r"output.*formats\[1\]"),
    ('pairs = [["hero", "dance"]]\n' + HEAD + OUTPUT, r"pairs\[0\]: no motion named 'dance'"),
    (HEAD + OUTPUT + '[[character]]\nname = "hero"\ndrawing = "hero.png"\n', r"'hero' is given twice"),
    (HEAD.replace('keys = "keys.json"', 'bvh = "keys.json"') + OUTPUT, r"needs 'view"),
    (HEAD + "[output\n", r"not valid TOML"),
])
def test_bad_keys_are_one_line_errors_naming_the_key(folder, text, match):
    with pytest.raises(BatchError, match=match) as raised:
        _load(folder, text)
    assert "\n" not in str(raised.value)


@pytest.mark.parametrize(("old", "new", "match"), [
    ('drawing = "hero.png"', 'drawing = "gone.png"', r"character\[0\]\.drawing: no such file .*gone\.png"),
    ('keys = "keys.json"', 'keys = "gone.json"', r"motion\[0\]\.keys: no such file .*gone\.json"),
    ('drawing = "hero.png"', 'project = "nowhere"', r"character\[0\]\.project: .*not a project folder"),
])
def test_missing_files_are_named(folder, old, new, match):
    with pytest.raises(BatchError, match=match) as raised:
        _load(folder, HEAD.replace(old, new) + OUTPUT)
    assert "\n" not in str(raised.value)


def test_several_outputs_need_names(folder):
    with pytest.raises(BatchError, match=r"output\[1\].name: several outputs need a name"):
        _load(folder, HEAD + '[[output]]\nname = "a"\nformats = ["gif"]\n[[output]]\nformats = ["glb"]\n')
