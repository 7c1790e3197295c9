"""A URDF's link tree checked before Pinocchio's parser sees it: unique link and joint names, every
joint's parent and child links declared, one parent per link, one root, and bounded size and depth
(the parser recurses per level and crashes the process on a chain of thousands of links). Each
problem is a ValueError naming the link or joint."""
from __future__ import annotations

import xml.etree.ElementTree as ET
from collections import Counter

__all__ = ["MAX_LINKS", "MAX_DEPTH", "check_tree"]

MAX_LINKS = 2000
#: deeper than any robot in example-robot-data (a humanoid's hand is ~15 links from its root)
MAX_DEPTH = 200


def _repeated(names: list[str | None], what: str) -> None:
    for name, count in Counter(names).items():
        if name is None:
            raise ValueError(f"a <{what}> without a name")
        if count > 1:
            raise ValueError(f"{what} {name!r} is declared {count} times")


def check_tree(root: ET.Element) -> None:
    """A ValueError if the <robot> element's links and joints do not form one bounded tree."""
    links = [e.get("name") for e in root.findall("link")]
    if len(links) > MAX_LINKS:
        raise ValueError(f"{len(links)} links; at most {MAX_LINKS} are read")
    _repeated(links, "link")
    joints = root.findall("joint")
    _repeated([e.get("name") for e in joints], "joint")
    known = set(links)
    parent_of: dict[str, tuple[str | None, str]] = {}
    for joint in joints:
        name = joint.get("name")
        ends: dict[str, str] = {}
        for end in ("parent", "child"):
            element = joint.find(end)
            link = None if element is None else element.get("link")
            if link is None:
                raise ValueError(f"joint {name!r} has no <{end} link=...>")
            if link not in known:
                raise ValueError(f"joint {name!r}: its {end} link {link!r} is not declared")
            ends[end] = link
        if ends["child"] in parent_of:
            raise ValueError(f"link {ends['child']!r} has two parents: joints {parent_of[ends['child']][0]!r} and {name!r}")
        parent_of[ends["child"]] = (name, ends["parent"])
    roots = [link for link in links if link not in parent_of]
    if len(roots) != 1:
        raise ValueError(f"{len(roots)} root links ({', '.join(map(repr, roots[:5]))}); a robot has one "
                         "(or the joints form a loop)" if roots else "the joints form a loop: no root link")
    for link in links:
        depth, at = 0, link
        while at in parent_of:
            at, depth = parent_of[at][1], depth + 1
            if depth > MAX_DEPTH:
                raise ValueError(f"link {link!r} is more than {MAX_DEPTH} joints from the root "
                                 "(or the joints form a loop)")
