"""Write docs/parameters.md, the reference page of the scene's parameters, from the tables the
scene readers check against (mpmsdem.parameters). Run after changing a table:

    PYTHONPATH=build/python /usr/bin/python3 scripts/gen_parameters.py [PATH]

PATH defaults to docs/parameters.md; tests/python/test_parameters.py fails while the committed
page differs from the generated one.
"""
import argparse
import os
import sys

from mpmsdem import parameters

ROOT = os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(__file__)), ".."))


def main(argv):
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("path", nargs="?", default=os.path.join(ROOT, "docs", "parameters.md"),
                    help="the page to write (default: docs/parameters.md)")
    path = ap.parse_args(argv[1:]).path
    with open(path, "w", encoding="utf-8") as f:
        f.write(parameters.markdown())
    print("wrote %s (%d parameters)" % (path, len(parameters.parameters())))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
