"""Every ```python block of README.md runs, so that the README cannot rot.

Each block runs in a fresh interpreter (this venv's), from a temporary directory.
A block whose first line is a comment starting with ``# continued`` continues the
block before it: the chain runs as one program. When a block is followed by a
```text block (blank lines between at most), that is its expected output: the
block's printed text must match with every number within ``RTOL`` (relative).
"""

import dataclasses
import math
import pathlib
import re
import subprocess
import sys

import pytest

README = pathlib.Path(__file__).resolve().parent.parent / "README.md"
#: Relative tolerance of printed numbers against a ```text block (printed
#: numbers differ from the README's by round-off and platform, not by more)
RTOL = 1e-6
TIMEOUT = 900  # s, per block (a first run compiles its forms)
CONTINUED = "# continued"
#: Printed before the last block of a chain: its output is what follows
MARKER = "--- xfem-contact README block ---"
FENCE = re.compile(r"^(`{3,}|~{3,})\s*([\w+-]*)")
NUMBER = re.compile(r"[-+]?(?:\d+\.\d*|\.\d+|\d+)(?:[eE][-+]?\d+)?")


@dataclasses.dataclass
class Block:
    language: str
    line: int  # of the opening fence, 1-based
    end: int  # of the closing fence, 1-based
    code: str
    expected: str | None = None  # the following ```text block
    previous: "Block | None" = None  # the block it continues

    @property
    def first_line(self) -> str:
        return next((s for s in self.code.splitlines() if s.strip()), "")

    def program(self) -> str:
        """The source to run: the chain of blocks this one continues, then it."""
        if self.previous is None:
            return self.code
        return f"{self.previous.program()}\nprint({MARKER!r}, flush=True)\n{self.code}"


def fenced_blocks(markdown: str) -> list[Block]:
    """The fenced code blocks of a markdown text, in order."""
    blocks, lines, i = [], markdown.splitlines(), 0
    while i < len(lines):
        opening = FENCE.match(lines[i])
        if opening is None:
            i += 1
            continue
        fence, body, start = opening.group(1), [], i
        i += 1
        while i < len(lines) and not lines[i].strip().startswith(fence):
            body.append(lines[i])
            i += 1
        code = "\n".join(body) + "\n"
        blocks.append(Block(opening.group(2).lower(), start + 1, i + 1, code))
        i += 1
    return blocks


def python_blocks(markdown: str) -> list[Block]:
    """The ```python blocks, with their expected output and the block each continues."""
    blocks, lines = fenced_blocks(markdown), markdown.splitlines()
    found: list[Block] = []
    for k, block in enumerate(blocks):
        if block.language != "python":
            continue
        after = blocks[k + 1] if k + 1 < len(blocks) else None
        between = lines[block.end : after.line - 1] if after else []
        if after and after.language == "text" and not "".join(between).strip():
            block.expected = after.code
        if block.first_line.startswith(CONTINUED):
            if not found:
                raise ValueError(f"README line {block.line}: nothing above to continue")
            block.previous = found[-1]
        found.append(block)
    return found


def same_output(printed: str, expected: str, rtol: float = RTOL) -> bool:
    """Same words, and numbers equal to ``rtol`` (relative)."""
    if NUMBER.sub("#", printed).split() != NUMBER.sub("#", expected).split():
        return False
    pairs = zip(NUMBER.findall(printed), NUMBER.findall(expected), strict=True)
    return all(math.isclose(float(a), float(b), rel_tol=rtol, abs_tol=0.0) for a, b in pairs)


def run(block: Block, cwd: pathlib.Path) -> None:
    """Run a block (with the chain it continues); AssertionError naming the block's
    README line and first line, with the interpreter's stderr, if it fails."""
    name = f"README.md line {block.line} ({block.first_line!r})"
    try:
        result = subprocess.run(
            [sys.executable, "-c", block.program()],
            cwd=cwd,
            capture_output=True,
            text=True,
            timeout=TIMEOUT,
        )
    except subprocess.TimeoutExpired as error:
        raise AssertionError(f"{name} did not finish in {TIMEOUT} s") from error
    if result.returncode != 0:
        raise AssertionError(f"{name} failed (exit {result.returncode}):\n{result.stderr}")
    if block.expected is not None:
        printed = result.stdout.rpartition(MARKER + "\n")[2] if block.previous else result.stdout
        if not same_output(printed, block.expected):
            raise AssertionError(
                f"{name} printed\n{printed}\nthe README's ```text block after it shows\n"
                f"{block.expected}(numbers compared to rtol {RTOL})"
            )


BLOCKS = python_blocks(README.read_text(encoding="utf-8"))
#: The documentation pages' own ```python blocks (the README's they include run above)
DOCS = sorted((README.parent / "docs").glob("*.md"))
DOC_BLOCKS = [(page.name, b) for page in DOCS for b in python_blocks(page.read_text("utf-8"))]


def test_readme_has_python_blocks():
    assert BLOCKS, "no ```python block found in README.md: is the parser broken?"


@pytest.mark.parametrize("block", BLOCKS, ids=[f"line{b.line}" for b in BLOCKS])
def test_readme_block(block, tmp_path):
    run(block, tmp_path)


@pytest.mark.parametrize(
    "page, block", DOC_BLOCKS, ids=[f"{page}:line{b.line}" for page, b in DOC_BLOCKS]
)
def test_docs_block(page, block, tmp_path):
    run(block, tmp_path)


# -- the harness itself --------------------------------------------------------

SAMPLE = """\
# Title

```python
x = 2.0
print(f"x = {x:.6f}, n = 3")
```

```text
x = 2.000000, n = 3
```

```sh
make test
```

```python
# continued: x from above
print(x + 1)
raise SystemExit(x > 1)
```

```python
1 / 0
```
"""


def test_parser():
    blocks = python_blocks(SAMPLE)
    assert [b.line for b in blocks] == [3, 16, 22]
    assert blocks[0].expected == "x = 2.000000, n = 3\n"
    assert blocks[1].expected is None and blocks[2].expected is None
    assert blocks[1].previous is blocks[0] and blocks[2].previous is None
    assert blocks[1].program().startswith("x = 2.0\n")


def test_output_comparison():
    assert same_output("x = 2.0000001, n = 3\n", "x = 2.000000, n = 3")
    assert not same_output("x = 2.00001, n = 3", "x = 2.000000, n = 3")  # beyond RTOL
    assert not same_output("x = 2.000000, n = 4", "x = 2.000000, n = 3")
    assert not same_output("y = 2.000000, n = 3", "x = 2.000000, n = 3")
    assert not same_output("x = 2.000000", "x = 2.000000, n = 3")


def test_harness_reports_failures(tmp_path):
    ok, continued, failing = python_blocks(SAMPLE)
    run(ok, tmp_path)
    with pytest.raises(AssertionError, match=r"line 16 \('# continued: x from above'\)"):
        run(continued, tmp_path)  # x > 1: exit 1
    with pytest.raises(AssertionError, match=r"line 22 \('1 / 0'\)[\s\S]*ZeroDivisionError"):
        run(failing, tmp_path)
    ok.expected = "x = 2.1, n = 3\n"
    with pytest.raises(AssertionError, match="printed"):
        run(ok, tmp_path)
