"""Line mutations shared by the ASF and AMC parser fuzz tests."""

MUTATIONS = ["replace", "delete", "dup", "tok", "ins"]


def mutate(lines: list[str], i: int, op: str, tok: str, j: int) -> str:
    """Apply one mutation ``op`` at line ``i`` (token ``tok``, word ``j``); return CRLF text."""
    lines = list(lines)
    if op == "replace":
        lines[i] = tok
    elif op == "delete":
        del lines[i]
    elif op == "dup":
        lines.insert(i, lines[i])
    elif op == "ins":
        lines.insert(i, tok)
    else:
        words = lines[i].split()
        if words:
            words[j % len(words)] = tok
        lines[i] = " ".join(words)
    return "\r\n".join(lines)
