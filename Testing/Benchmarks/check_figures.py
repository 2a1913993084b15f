#!/usr/bin/env python3
"""Runs a benchmark and checks the figures it prints against bounds.

    check_figures.py --figure NAME REGEX LOW HIGH [--figure ...] [--text TEXT ...] -- COMMAND ...

REGEX has one group that captures a number; every line it matches must give a number within
[LOW, HIGH] ('-' for no bound), and it must match at least once. Each --text must appear in the
output. The figures bounded are accuracies, counts and sizes, never times: a loaded machine
must not fail the suite.
"""
import re
import subprocess
import sys


def parse(argv):
    if "--" not in argv:
        sys.exit("usage: check_figures.py [--figure NAME REGEX LOW HIGH] [--text TEXT] -- COMMAND")
    split = argv.index("--")
    options, command = argv[:split], argv[split + 1:]
    figures, texts = [], []
    i = 0
    while i < len(options):
        if options[i] == "--figure":
            name, regex, low, high = options[i + 1:i + 5]
            bound = lambda b: None if b == "-" else float(b)
            figures.append((name, re.compile(regex), bound(low), bound(high)))
            i += 5
        elif options[i] == "--text":
            texts.append(options[i + 1])
            i += 2
        else:
            sys.exit(f"check_figures.py: unknown option {options[i]}")
    return figures, texts, command


def main():
    figures, texts, command = parse(sys.argv[1:])
    run = subprocess.run(command, capture_output=True, text=True)
    sys.stdout.write(run.stdout)
    sys.stderr.write(run.stderr)
    failures = []
    if run.returncode != 0:
        failures.append(f"the benchmark exited with status {run.returncode}")
    for name, regex, low, high in figures:
        values = [float(m.group(1)) for m in regex.finditer(run.stdout)]
        if not values:
            failures.append(f"{name}: not printed (pattern {regex.pattern!r})")
        for v in values:
            if (low is not None and v < low) or (high is not None and v > high):
                failures.append(f"{name}: {v:g} outside [{low}, {high}]")
    for text in texts:
        if text not in run.stdout:
            failures.append(f"missing from the output: {text!r}")
    for f in failures:
        print(f"FIGURE CHECK FAILED: {f}")
    if not failures:
        print(f"figures within bounds: {len(figures)} figures, {len(texts)} texts")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
