"""The executed-example harness itself: the page convention is parsed as written, and an
output that drifts from its page fails (tests/docs/examples.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from tests.docs.examples import (
    Command,
    FileWrite,
    PythonBlock,
    drift_message,
    output_matches,
    page_steps,
)

PAGE = """# A page

```console
$ echo one
one
$ false  # exit 1
$ printf 'a\\nb\\n' \\
    | cat
a
b
```

<!-- example: skip -->
```console
$ pip install something
```

<!-- example: slow -->
```console
$ sleep 1
```

```toml
# file: sub/x.toml
name = "x"
```

  - a list item with a nested block:

    ```python
    >>> 1 + 1
    2
    ```

```sh
$ shown only
```
"""


def test_the_convention_is_parsed_as_written(tmp_path: Path):
    page = tmp_path / "page.md"
    page.write_text(PAGE)
    steps = page_steps(page)
    assert [type(s) for s in steps] == [Command, Command, Command, Command, FileWrite,
                                        PythonBlock]
    echo, false, pipe, sleep, toml, doc = steps
    assert (echo.command, echo.expected, echo.status, echo.line) == ("echo one", "one", 0, 4)
    assert (false.command, false.status) == ("false", 1)
    assert pipe.command == "printf 'a\\nb\\n' \\\n    | cat" and pipe.expected == "a\nb"
    assert sleep.slow and not echo.slow
    assert toml.name == "sub/x.toml" and toml.text.startswith("# file: sub/x.toml\n")
    assert doc.doctest and doc.source.startswith(">>> 1 + 1")


@pytest.mark.parametrize(("expected", "actual", "matches"), [
    ("a\nb", "a\nb\n\n", True),                       # blank lines at the ends
    ("a  \nb", "a\nb   ", True),                      # trailing spaces
    ("a\n...\nd", "a\nb\nc\nd", True),                # a line `...`: any lines
    ("a\n...\nb", "a\nb", True),                      # ... or none
    ("x = ... m", "x = 0.25 m", True),                # `...` in a line: any text
    ("x = ... m", "x = 0.25\nm", False),              # ... on that line only
    ("a\nb", "a\nc", False),
    ("a", "a\nb", False),                             # extra output is a drift
    ("", "", True),
    ("", "something", False),                         # a silent command must stay silent
])
def test_output_matching(expected, actual, matches):
    assert output_matches(expected, actual) is matches


def test_a_drift_message_shows_the_diff():
    step = Command(12, "xval solve x", "T = 0.673338 N m", 0, False)
    message = drift_message("README.md", step, "T = 0.673339 N m\n", 0)
    assert message.startswith("README.md:12: `$ xval solve x` printed other output")
    assert "-T = 0.673338 N m" in message and "+T = 0.673339 N m" in message
    status = drift_message("README.md", step, "T = 0.673338 N m\n", 2)
    assert "exited with status 2, the page expects 0" in status
