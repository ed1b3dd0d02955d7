"""The scene's parameters, each declared once, in the C++ tables the scene readers check against
(the flow model's in pkg/mpm/MpmParameters.cpp, the scene's own in pkg/scene/SceneParameters.cpp,
the blocks' in pkg/coupling/BlockParameters.cpp):
its key in the JSON scene, its name in the Python API, unit, default, range, the paper's
equation and its meaning.

    mpmsdem.parameters.parameters("material")   # the entries of a section, as dicts
    mpmsdem.parameters.pythonNames("run")       # {"outputEvery": "output_every", ...}

``scripts/gen_parameters.py`` writes the reference page, docs/parameters.md, from them
(tests/python/test_parameters.py checks that the committed page is the generated one).
"""
from . import _mpmsdem

_ALL = tuple(_mpmsdem.parameters())


def sectionOf(key):
    """The section of a key: ``"material"`` for ``"material.mu_s"``, ``""`` at the top level."""
    return key.rpartition(".")[0]


def parameters(section=None):
    """The entries (dicts: table, key, leaf, python, kind, unit, required, default, defaultText, lo,
    hi, loInclusive, hiInclusive, range, choices, equation, doc), in table order: all of them, or
    those right under ``section`` (``""``: the top level; ``"flow_probes[]"``: a probe's)."""
    return [dict(p) for p in _ALL if section is None or sectionOf(p["key"]) == section]


def parameter(key):
    """The entry of ``key`` (e.g. ``"material.mu_s"``); KeyError when there is none."""
    for p in _ALL:
        if p["key"] == key:
            return dict(p)
    raise KeyError("no scene parameter %r" % key)


def pythonNames(section):
    """``{Python name: scene key}`` of the values right under ``section`` (not its objects), in
    table order: how the Python API's keywords map onto the scene's keys."""
    return {p["python"]: p["leaf"] for p in parameters(section) if p["kind"] != "object" and p["python"]}


def _cell(text):
    return str(text).replace("|", "\\|")


def _code(text):
    return "`%s`" % text if text else ""


def _parent(section):
    """The entry that describes a section: ``particles`` for ``particles[]``, ``block_materials``
    for ``block_materials.<name>``."""
    keys = {p["key"] for p in _ALL}
    for candidate in (section, section[:-2] if section.endswith("[]") else None, sectionOf(section)):
        if candidate in keys:
            return parameter(candidate)
    return None


_TITLES = {"scene": "The flow's scene", "blocks": "The blocks of a coupled scene"}


def markdown():
    """docs/parameters.md: one table per section (key, Python name, unit, default, range,
    equation, meaning)."""
    out = ["# Scene parameters", "",
           "Every key of a JSON scene (the `mpmsdem-run` driver's, and the scene an `MpmEngine` builds from its "
           "arguments), each with its name in the Python API, unit, default, allowed range, the paper's equation "
           "and its meaning. A value out of its range is refused with a `ParameterError` (`ValueError` in Python) "
           "naming the key and the range given here.", "",
           "Generated from the tables the scene readers and the solver check against (`pkg/mpm/MpmParameters.cpp`, "
           "`pkg/scene/SceneParameters.cpp`, `pkg/coupling/BlockParameters.cpp`) by `scripts/gen_parameters.py`; "
           "do not edit by hand. The schema with examples: `pkg/scene/MpmScene.hpp`, "
           "`pkg/coupling/CoupledScene.hpp`; the Python API: [api.md](api.md).", ""]
    tables = []
    for p in _ALL:
        if p["table"] not in tables:
            tables.append(p["table"])
    for table in tables:
        out += ["## " + _TITLES.get(table, table), ""]
        sections = []
        for p in _ALL:
            s = sectionOf(p["key"])
            if p["table"] == table and s not in sections:
                sections.append(s)
        for section in sections:
            parent = _parent(section) if section else None
            out += ["### " + ("`%s`" % section if section else "Top level"), ""]
            if parent is not None:
                where = " Python: `%s`." % parent["python"] if parent["python"] else ""
                doc = parent["doc"]
                out += [_cell(doc[:1].upper() + doc[1:]) + "." + where, ""]
            out += ["| Key | Python | Unit | Default | Range | Equation | Meaning |",
                    "|---|---|---|---|---|---|---|"]
            for p in parameters(section):
                if p["table"] != table:
                    continue
                default = p["defaultText"]
                if p["kind"] == "choice" and default:
                    default = '"%s"' % default
                out.append("| %s |" % " | ".join(_cell(c) for c in (
                    _code(p["leaf"]), _code(p["python"]), p["unit"], default, p["range"], p["equation"], p["doc"])))
            out.append("")
    return "\n".join(out)
