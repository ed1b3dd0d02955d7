"""Inputs from elsewhere never crash the Python readers: property-based fuzzing (hypothesis) of
the block table (CSV) and of the SDEM checkpoint (sdem.json). Every input is either read, with
every value checked, or refused with a ValueError that names the file, the place and what is
wrong; any other exception is a defect. Each test sees FUZZ_EXAMPLES inputs (1,000 in CI;
10,000 for the figures of docs/extremes.md, "Fuzzing"), built from mutations of valid files and
from arbitrary text and JSON, with a fixed seed so that a failure replays."""
import json
import math
import os
import string

import pytest
from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

from mpmsdem import field

EXAMPLES = int(os.environ.get("FUZZ_EXAMPLES", "1000"))
FUZZ = settings(max_examples=EXAMPLES, deadline=None, database=None, derandomize=False,
                suppress_health_check=list(HealthCheck))

NUMBER = st.one_of(st.floats(allow_nan=True, allow_infinity=True), st.integers(-10 ** 20, 10 ** 20),
                   st.sampled_from(["", " ", "1e309", "-0", "nan", "inf", "0x10", "1,5", "++1"]))
FIELD = st.one_of(NUMBER.map(str), st.text(max_size=12),
                  st.sampled_from(["box:1x2x3", "box:0x1x1", "box:1x1", "box:axbxc", "car.obj", "car.obj*2",
                                   "car.obj*x", "car.obj*-1", "car.stl*nan", "rock.ply", ""]))
ROW = st.lists(FIELD, min_size=0, max_size=8)
HEADERS = st.one_of(st.just(list(field.COLUMNS)), st.permutations(list(field.COLUMNS)),
                    st.lists(st.sampled_from(list(field.COLUMNS) + ["extra", ""]), max_size=8))


def _csvText(header, rows):
    quote = lambda v: '"%s"' % v.replace('"', '""') if any(c in v for c in ',"\n\r') else v  # noqa: E731
    return "\n".join(",".join(quote(v) for v in r) for r in [header] + rows) + "\n"


def _readTable(tmp_path, data):
    path = str(tmp_path / "blocks.csv")
    with open(path, "wb") as f:
        f.write(data)
    try:
        rows = field.readBlockTable(path)
    except ValueError as e:
        assert str(e).startswith("block table %s" % path), "the message does not name the file: %s" % e
        return None
    for r in rows:  # read: every value as documented
        assert isinstance(r["id"], int) and r["mass"] > 0
        assert all(math.isfinite(r[k]) for k in ("x", "y", "heading_deg", "mass"))
    assert len({r["id"] for r in rows}) == len(rows)
    return rows


@seed(20261129)
@FUZZ
@given(header=HEADERS, rows=st.lists(ROW, max_size=6))
def test_block_table_structured(tmp_path_factory, header, rows):
    _readTable(tmp_path_factory.mktemp("t"), _csvText(header, rows).encode())


@seed(20261130)
@FUZZ
@given(data=st.one_of(st.binary(max_size=400),
                      st.text(alphabet=string.printable, max_size=400).map(str.encode)))
def test_block_table_arbitrary_bytes(tmp_path_factory, data):
    _readTable(tmp_path_factory.mktemp("t"), b"id,shape,x,y,heading_deg,mass\n" + data)


JSON = st.recursive(st.none() | st.booleans() | st.floats(allow_nan=False) | st.integers() | st.text(max_size=8),
                    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner,
                                                                               max_size=4), max_leaves=12)


def _validCheckpoint():
    """A real sdem.json of a one-box scene: the documented format to mutate."""
    import mpmsdem
    from yade import O
    O.reset()
    eng = mpmsdem.SdemEngine(verbose=False)
    mat = mpmsdem.material(density=2000, friction=0.3)
    eng.box((0.1, 0.1, 0.1), 0.005, mat, pos=(0, 0, 0))
    import tempfile
    d = tempfile.mkdtemp()
    eng.save(os.path.join(d, "sdem.json"))
    with open(os.path.join(d, "sdem.json")) as f:
        return json.load(f)


VALID = None


def _mutations(doc):
    """Each key of the valid document replaced by arbitrary JSON, or removed."""
    keys = sorted(doc)
    return st.tuples(st.sampled_from(keys), st.one_of(JSON, st.just("<removed>")))


@pytest.mark.parametrize("mode", ["mutated", "arbitrary"])
def test_sdem_checkpoint(tmp_path, mode):
    import mpmsdem
    global VALID
    VALID = VALID or _validCheckpoint()
    path = str(tmp_path / "sdem.json")
    strategy = (st.tuples(_mutations(VALID), _mutations(VALID)) if mode == "mutated"
                else st.one_of(JSON, st.dictionaries(st.sampled_from(sorted(VALID) + ["x"]), JSON, max_size=6)))

    @seed(20261131)
    @FUZZ
    @given(m=strategy)
    def one(m):
        if mode == "mutated":
            doc = json.loads(json.dumps(VALID))
            for key, value in m:
                if value == "<removed>":
                    doc.pop(key, None)
                else:
                    doc[key] = value
        else:
            doc = m
        with open(path, "w") as f:
            json.dump(doc, f)
        try:
            mpmsdem.SdemEngine.restore(path, verbose=False)
        except ValueError as e:
            assert repr(path) in str(e) or path in str(e), "the message does not name the file: %s" % e

    one()


def test_what_the_fuzzing_found_is_refused_by_name(tmp_path):
    """The inputs the fuzzing found before the fixes: a checkpoint without its bodies (a
    KeyError), one that is a JSON list (an AttributeError), a block table row shorter than its
    header (an AttributeError on None)."""
    import mpmsdem
    global VALID
    VALID = VALID or _validCheckpoint()
    path = tmp_path / "sdem.json"
    for doc, words in ((dict(VALID, bodies=None), "not a whole mpmsdem SDEM checkpoint (TypeError"),
                       ({k: v for k, v in VALID.items() if k != "bodies"}, "(KeyError: 'bodies')"),
                       ([1, 2], "not an mpmsdem SDEM checkpoint (a JSON list, not an object)")):
        path.write_text(json.dumps(doc))
        with pytest.raises(ValueError) as e:
            mpmsdem.SdemEngine.restore(str(path), verbose=False)
        assert str(e.value).startswith("path = %r: " % str(path)) and words in str(e.value), str(e.value)
    path.write_text("{not json")
    with pytest.raises(ValueError, match="sdem.json': Expecting property name"):
        mpmsdem.SdemEngine.restore(str(path), verbose=False)
    table = tmp_path / "blocks.csv"
    table.write_text("id,shape,x,y,heading_deg,mass\n-0\n")
    with pytest.raises(ValueError, match="line 2: 1 values for the 6 columns"):
        field.readBlockTable(str(table))
