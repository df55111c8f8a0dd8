"""The Python snippets of docs/python.md run, in order, and show what the page says they show:
the value of the last expression (its repr), what print() wrote, or the error raised. After a
change that alters what they show, ZEROSET_UPDATE_DOCS=1 writes the new results into the page
(then read the diff before committing it)."""
import ast
import contextlib
import io
import os
import pathlib
import re

import pytest

PAGE = pathlib.Path(__file__).resolve().parents[2] / "docs" / "python.md"


def snippets():
    """(code, shown) pairs: each ```python block and the plain ``` block right after it."""
    text = PAGE.read_text()
    pairs = re.findall(r"```python\n(.*?)```\n```\n(.*?)```", text, flags=re.S)
    assert len(pairs) >= 10, f"{PAGE}: expected the walk-through's snippets, found {len(pairs)}"
    return pairs


def run(code, namespace):
    """Runs `code` as a notebook cell: returns the repr of a last expression and what it
    printed."""
    tree = ast.parse(code)
    last = tree.body.pop() if tree.body and isinstance(tree.body[-1], ast.Expr) else None
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        exec(compile(tree, "docs/python.md", "exec"), namespace)
        value = eval(compile(ast.Expression(last.value), "docs/python.md", "eval"),
                     namespace) if last else None
    shown = out.getvalue()
    if value is not None:
        shown += repr(value) + "\n"
    return shown


def test_the_python_pages_snippets_show_what_it_says(tmp_path, monkeypatch):
    # The snippets save pictures under docs/img/ and files beside them: in a scratch directory.
    monkeypatch.chdir(tmp_path)
    (tmp_path / "docs" / "img").mkdir(parents=True)
    namespace = {}
    page = PAGE.read_text()
    wrong = []
    for number, (code, shown) in enumerate(snippets(), 1):
        error = re.match(r"(\w+Error): (.*)", shown, flags=re.S)
        try:
            actual = run(code, namespace)
        except Exception as e:  # noqa: BLE001 - the page may show an error
            actual = f"{type(e).__name__}: {e}\n"
            if not error:
                raise AssertionError(f"docs/python.md, snippet {number} raised:\n{code}") from e
        if actual != shown:
            wrong.append(f"snippet {number}:\n{code}shows:\n{shown}but gives:\n{actual}")
            page = page.replace(f"```python\n{code}```\n```\n{shown}```",
                                f"```python\n{code}```\n```\n{actual}```", 1)
    if wrong and os.environ.get("ZEROSET_UPDATE_DOCS") == "1":
        PAGE.write_text(page)
    assert not wrong, "docs/python.md:\n\n" + "\n".join(wrong)
