"""Units sized for one job: no product source file over 600 lines, no C++ function over 50 (from
the line of its opening brace to that of its closing one). The product's sources are the engine,
the VTK filters, the applications, the plugin, the wrapping and the examples; tests and
benchmarks are not held to it. Functions are found by the house style (.clang-format: Allman
braces), so a body is a `{` alone on its line at the indentation of a definition: a free or
out-of-class function (column 0) or one defined in a class body (column 2), after a line that
is neither a type, a namespace nor a statement of control flow."""
import os
import re
import unittest

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
PRODUCT = ("Filters", "Applications", "ParaViewPlugin", "Wrapping", "Examples")
SOURCE_SUFFIXES = (".cxx", ".h", ".py", ".js", ".mjs", ".html", ".css", ".sh")
CXX_SUFFIXES = (".cxx", ".h")
MAX_FILE_LINES = 600
MAX_FUNCTION_LINES = 50
NOT_A_FUNCTION = re.compile(
    r"^\s*((class|struct|namespace|enum|union)\b|(for|if|while|switch|do|try|catch|else)\b)|=\s*$")


def product_sources():
    for top in PRODUCT:
        for folder, _, files in os.walk(os.path.join(ROOT, top)):
            for name in sorted(files):
                if name.endswith(SOURCE_SUFFIXES):
                    yield os.path.join(folder, name)


def function_lengths(lines):
    """[(first line number, length, signature)] of the function bodies in `lines`."""
    found = []
    for i, line in enumerate(lines):
        opening = re.match(r"^( {0,2})\{\s*$", line)
        if not opening or i == 0 or NOT_A_FUNCTION.search(lines[i - 1]):
            continue
        if ")" not in lines[i - 1] and "const" not in lines[i - 1]:
            continue  # an initialiser or a block, not a definition
        closing = re.compile("^" + opening.group(1) + r"\}")
        end = next((j for j in range(i + 1, len(lines)) if closing.match(lines[j])), len(lines) - 1)
        start = i - 1
        while start > 0 and "(" not in lines[start]:
            start -= 1
        found.append((i + 1, end - i + 1, lines[start].strip()))
    return found


class UnitSizes(unittest.TestCase):
    maxDiff = None

    def test_no_product_source_file_is_over_the_bound(self):
        long_files = []
        for path in product_sources():
            with open(path, errors="replace") as f:
                count = sum(1 for _ in f)
            if count > MAX_FILE_LINES:
                long_files.append(f"{os.path.relpath(path, ROOT)}: {count} lines")
        self.assertEqual(long_files, [], f"files over {MAX_FILE_LINES} lines")

    def test_no_function_is_over_the_bound(self):
        long_functions = []
        for path in product_sources():
            if not path.endswith(CXX_SUFFIXES):
                continue
            with open(path) as f:
                lines = f.read().split("\n")
            for line, length, signature in function_lengths(lines):
                if length > MAX_FUNCTION_LINES:
                    long_functions.append(
                        f"{os.path.relpath(path, ROOT)}:{line}: {length} lines: {signature}")
        self.assertEqual(long_functions, [], f"functions over {MAX_FUNCTION_LINES} lines")

    def test_the_function_finder_measures_what_the_style_writes(self):
        # The finder itself: a free function, a member defined in its class, and a loop's block
        # inside a function (not a function of its own), measured as written.
        text = ("int free(int a)\n{\n  for (int i = 0; i < a; ++i)\n  {\n    a += i;\n  }\n"
                "  return a;\n}\n\nstruct S\n{\n  int member() const\n  {\n    return 1;\n  }\n};\n")
        found = [(line, length) for line, length, _ in function_lengths(text.split("\n"))]
        self.assertEqual(found, [(2, 7), (13, 3)])


if __name__ == "__main__":
    unittest.main()
