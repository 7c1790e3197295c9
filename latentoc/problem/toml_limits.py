"""Bounds checked on a problem file before the TOML parser sees it: its size, the nesting of its
arrays and inline tables, and the parts of a dotted key. Python's parser recurses per nesting level
and keeps every dotted part, so a hostile file exhausts the stack or gigabytes of memory before
it fails; a problem file needs a few kilobytes, a few levels and a few parts."""
from __future__ import annotations

__all__ = ["MAX_BYTES", "MAX_DEPTH", "MAX_KEY_PARTS", "toml_bounds_problem"]

MAX_BYTES = 1_000_000
MAX_DEPTH = 32
MAX_KEY_PARTS = 32


def toml_bounds_problem(text: str) -> str | None:
    """What in ``text`` is beyond the bounds (module doc), or None: a scan outside strings and
    comments of the bracket depth and the dots of each key."""
    if len(text.encode("utf-8", "surrogatepass")) > MAX_BYTES:
        return f"larger than {MAX_BYTES // 1000} kB; a problem file needs a few kB"
    depth, line, parts, in_key, i, n = 0, 1, 1, True, 0, len(text)
    while i < n:
        c = text[i]
        if c in "\"'":
            quote = c * 3 if text.startswith(c * 3, i) else c
            i += len(quote)
            while i < n and not text.startswith(quote, i):
                if c == '"' and text[i] == "\\":
                    i += 1
                line += text[i] == "\n" if i < n else 0
                i += 1
            i += len(quote)
            continue
        if c == "#":
            while i < n and text[i] != "\n":
                i += 1
            continue
        if c == "\n":
            line += 1
            if depth == 0:
                in_key, parts = True, 1
        elif c in "[{":
            depth += 1
            if depth > MAX_DEPTH:
                return f"line {line}: arrays or tables nested deeper than {MAX_DEPTH} levels"
            if c == "{":
                in_key, parts = True, 1
        elif c in "]}":
            depth = max(depth - 1, 0)
        elif c == "," and depth:
            in_key, parts = True, 1
        elif c == "=" and in_key:
            in_key = False
        elif c == "." and in_key:
            parts += 1
            if parts > MAX_KEY_PARTS:
                return f"line {line}: a key of more than {MAX_KEY_PARTS} dotted parts"
        i += 1
    return None
