#!/usr/bin/env python3
"""Lists C++ function definitions longer than a limit (lines from signature to closing brace).

    scripts/function_lengths.py [--max 120] [--top N] [PATH ...]   # default: src apps python

Exit status 1 when a function is longer than --max (the project's limit is 120 lines), so the
test suite can hold the limit. A lexical scan, not a compiler: comments, strings and character
literals are blanked, then braces are matched. A brace opens a function body when it follows a
parenthesised header at namespace or class scope; lambdas and blocks inside count toward their
enclosing function.
"""
import argparse
import os
import re
import sys

CONTAINER_KEYWORDS = ("namespace", "class", "struct", "union", "enum", "extern")


def blank_comments_and_strings(text):
    """Replaces comments and string/char literals by spaces, keeping newlines (line numbers)."""
    out = []
    i, n = 0, len(text)
    while i < n:
        c = text[i]
        if text.startswith("//", i):
            j = text.find("\n", i)
            j = n if j < 0 else j
            out.append(" " * (j - i))
            i = j
        elif text.startswith("/*", i):
            j = text.find("*/", i + 2)
            j = n if j < 0 else j + 2
            out.append(re.sub(r"[^\n]", " ", text[i:j]))
            i = j
        elif c == 'R' and text.startswith('R"', i) and (i == 0 or not (text[i - 1].isalnum() or text[i - 1] == "_")):
            m = re.match(r'R"([^(\s]{0,16})\(', text[i:])
            if not m:
                out.append(c)
                i += 1
                continue
            end = ")" + m.group(1) + '"'
            j = text.find(end, i + m.end())
            j = n if j < 0 else j + len(end)
            out.append('""' + re.sub(r"[^\n]", " ", text[i + 2:j]))
            i = j
        elif c in "\"'":
            # A digit separator (1'000) is not a character literal.
            if c == "'" and i > 0 and text[i - 1].isalnum() and i + 1 < n and text[i + 1].isalnum() \
                    and text[i - 1].isdigit():
                out.append(c)
                i += 1
                continue
            j = i + 1
            while j < n and text[j] != c and text[j] != "\n":
                j += 2 if text[j] == "\\" else 1
            j = min(j + 1, n)
            out.append(c + " " * (j - i - 2) + c if j - i >= 2 else c)
            i = j
        elif c == "#" and (i == 0 or text[i - 1] == "\n" or text[:i].rstrip(" \t").endswith("\n")):
            # Preprocessor line (with continuations): blanked.
            j = i
            while True:
                k = text.find("\n", j)
                if k < 0:
                    k = n
                    break
                if text[k - 1] == "\\":
                    j = k + 1
                    continue
                break
            out.append(re.sub(r"[^\n]", " ", text[i:k]))
            i = k
        else:
            out.append(c)
            i += 1
    return "".join(out)


def header_kind(header):
    """'container', 'function' or 'other' for the text before a '{' at namespace/class scope."""
    h = re.sub(r"\s+", " ", header).strip()
    h = re.sub(r"^(template ?<[^{;]*?> ?)+", "", h)
    first = h.split(" ", 1)[0] if h else ""
    if first in CONTAINER_KEYWORDS or re.match(r"^(typedef |using )?(class|struct|union|enum)\b", h):
        return "container"
    if "(" not in h:
        return "other"
    before_paren = h.split("(", 1)[0]
    if "=" in before_paren and "operator" not in before_paren:
        return "other"  # an initialiser, e.g. `auto f = [](...) {` or `T x = Make({...})`
    if first in ("if", "for", "while", "switch", "catch", "do", "else", "return"):
        return "other"
    return "function"


def function_name(header):
    h = re.sub(r"\s+", " ", header).strip()
    m = re.search(r"([~\w:]+(?:operator\s*[^\s(]+)?)\s*\(", h)
    return m.group(1) if m else h[:40]


def functions(path):
    with open(path, encoding="utf-8", errors="replace") as f:
        text = blank_comments_and_strings(f.read())
    results = []
    stack = []  # entries: ("container"|"function"|"other", start_line, name)
    stmt_start = 0
    line = 1
    depth_paren = 0
    for i, c in enumerate(text):
        if c == "\n":
            line += 1
        elif c in "([":
            depth_paren += 1
        elif c in ")]":
            depth_paren = max(0, depth_paren - 1)
        elif c == ";" and depth_paren == 0:
            stmt_start = i + 1
        elif c == "{":
            in_code = any(k == "function" for k, _, _ in stack)
            if in_code:
                stack.append(("other", line, ""))
            else:
                header = text[stmt_start:i]
                kind = header_kind(header)
                start = line - header.rstrip().count("\n") if kind == "function" else line
                # The header's first non-blank line.
                if kind == "function":
                    lead = header[: len(header) - len(header.lstrip())]
                    start = line - header.count("\n") + lead.count("\n")
                stack.append((kind, start, function_name(header) if kind == "function" else ""))
            stmt_start = i + 1
            depth_paren = 0
        elif c == "}":
            if stack:
                kind, start, name = stack.pop()
                if kind == "function":
                    results.append((line - start + 1, path, start, name))
            stmt_start = i + 1
            depth_paren = 0
    return results


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("paths", nargs="*", default=["src", "apps", "python"])
    parser.add_argument("--max", type=int, default=120, help="longest allowed function (lines)")
    parser.add_argument("--top", type=int, default=0, help="also list the N longest functions")
    args = parser.parse_args()
    files = []
    for p in args.paths:
        if os.path.isfile(p):
            files.append(p)
            continue
        for root, _, names in os.walk(p):
            files += [os.path.join(root, n) for n in names if n.endswith((".cc", ".h", ".cpp", ".hpp"))]
    found = []
    for f in sorted(files):
        found += functions(f)
    found.sort(key=lambda r: -r[0])
    too_long = [r for r in found if r[0] > args.max]
    shown = found[: max(args.top, len(too_long))]
    for length, path, start, name in shown:
        mark = " (over the limit)" if length > args.max else ""
        print(f"{length:5d}  {path}:{start}  {name}{mark}")
    print(f"{len(found)} functions, {len(too_long)} over {args.max} lines"
          + (f", the longest {found[0][0]} ({found[0][3]})" if found else ""))
    return 1 if too_long else 0


if __name__ == "__main__":
    sys.exit(main())
