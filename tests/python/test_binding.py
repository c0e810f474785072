"""The ctypes mirror of csculpt.h: every function bound with the header's types, every struct
laid out as the C compiler lays it out, every enum value, and the load-time version check."""

import ctypes
import importlib.util
import itertools
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest
from ctypes import POINTER

import meshes
import csculpt


def header_text():
    with open(meshes.HEADER, encoding="utf-8") as f:
        text = f.read()
    # Comments mention names and parentheses; only declarations count.
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def declared_functions():
    """{name: (return type, [parameter types])} of every CSC_API function, as C spells them."""
    functions = {}
    for m in re.finditer(r"CSC_API\s+([^;(]*?)\b(csc_\w+)\s*\(([^)]*)\)\s*;", header_text()):
        ret, name, params = m.group(1).strip(), m.group(2), m.group(3).strip()
        params = [] if params == "void" else [p.strip() for p in params.split(",")]
        # Drop each parameter's name: the last identifier after the type.
        params = [re.sub(r"\s*\b\w+$", "", p) if re.search(r"[\w*]\s+\w+$", p) else p
                  for p in params]
        functions[name] = (ret, params)
    return functions


_BASES = {
    "uint8_t": ctypes.c_uint8, "uint32_t": ctypes.c_uint32, "uint64_t": ctypes.c_uint64,
    "int32_t": ctypes.c_int32, "size_t": ctypes.c_size_t, "float": ctypes.c_float,
    "double": ctypes.c_double, "csc_status": ctypes.c_int, "csc_linearisation": ctypes.c_int,
    "csc_merge_method": ctypes.c_int, "csc_event_kind": ctypes.c_int,
}


def ctype_of(c_type):
    """The ctypes type a C type must be declared as (None for void)."""
    stars = c_type.count("*")
    base = re.sub(r"\bconst\b|\*", " ", c_type).split()
    assert len(base) == 1, c_type
    base = base[0]
    if base == "void":
        if stars == 0:
            return None
        t, stars = ctypes.c_void_p, stars - 1
    elif base == "char":
        assert stars >= 1, c_type
        t, stars = ctypes.c_char_p, stars - 1
    elif base.startswith("csc_") and base not in _BASES:
        t = getattr(csculpt, base)  # opaque handle or struct mirror, named as in C
    else:
        t = _BASES[base]
    for _ in range(stars):
        t = POINTER(t)
    return t


class Prototypes(unittest.TestCase):

    def test_every_function_of_the_header_is_declared_with_its_types(self):
        declared = declared_functions()
        self.assertGreaterEqual(len(declared), 40)  # the regex found the declarations
        self.assertEqual(sorted(declared), sorted(csculpt.PROTOTYPES))
        lib = csculpt._lib
        for name, (ret, params) in declared.items():
            with self.subTest(function=name):
                func = getattr(lib, name)
                self.assertEqual(list(func.argtypes), [ctype_of(p) for p in params])
                if ret == "csc_status":
                    self.assertIs(func.restype, ctypes.c_int)
                    self.assertIs(func.errcheck, csculpt._errcheck)
                else:
                    self.assertIs(func.restype, ctype_of(ret))

    def test_the_type_parser_reads_the_tricky_declarations(self):
        # The comparison above is only as good as this parser.
        declared = declared_functions()
        self.assertEqual(declared["csc_merger_merge"][1],
                         ["csc_merger*", "csc_diff**", "const csc_mesh*", "const csc_diff* const*",
                          "uint32_t", "const csc_merge_options*"])
        self.assertEqual(declared["csc_version"], ("uint32_t", []))
        self.assertEqual(ctype_of("const csc_diff* const*"), POINTER(POINTER(csculpt.csc_diff)))
        self.assertEqual(ctype_of("const char**"), POINTER(ctypes.c_char_p))


def probe_lines():
    probe = os.environ.get("CSCULPT_LAYOUT_PROBE")
    if not probe:
        compiler = shutil.which("cc") or shutil.which("gcc")
        if compiler is None:
            raise unittest.SkipTest("no CSCULPT_LAYOUT_PROBE and no C compiler to build it")
        tmp = tempfile.mkdtemp()
        probe = os.path.join(tmp, "probe")
        subprocess.run([compiler, "-std=c99", "-I", os.path.dirname(meshes.HEADER),
                        os.path.join(meshes.HERE, "layout_probe.c"), "-o", probe], check=True)
    out = subprocess.run([probe], check=True, capture_output=True, text=True).stdout
    return [line.split() for line in out.splitlines()]


class Layout(unittest.TestCase):

    @classmethod
    def setUpClass(cls):
        cls.lines = probe_lines()

    def test_every_struct_has_the_c_size_and_offsets(self):
        sizes = {s: int(n) for kind, s, n in (l for l in self.lines if l[0] == "size")}
        fields = {}
        for kind, s, f, offset, size in (l for l in self.lines if l[0] == "field"):
            fields.setdefault(s, []).append((f, int(offset), int(size)))
        structs = set(re.findall(r"typedef struct (csc_\w+) \{", header_text()))
        self.assertEqual(set(sizes), structs, "the probe must cover every struct of the header")
        for name, size in sizes.items():
            with self.subTest(struct=name):
                mirror = getattr(csculpt, name)
                self.assertEqual(ctypes.sizeof(mirror), size)
                self.assertEqual([f for f, _, _ in fields[name]], [f for f, _ in mirror._fields_])
                for f, offset, fsize in fields[name]:
                    self.assertEqual(getattr(mirror, f).offset, offset, f)
                    self.assertEqual(getattr(mirror, f).size, fsize, f)

    def test_new_structs_match_the_init_macros(self):
        inits = [l for l in self.lines if l[0] == "init"]
        self.assertGreater(len(inits), 15)
        for _, name, field, value in inits:
            with self.subTest(struct=name, field=field):
                self.assertEqual(float(getattr(getattr(csculpt, name)(), field)), float(value))


class Enums(unittest.TestCase):

    def test_every_enumerator_has_the_header_value(self):
        text = header_text()
        enums = {"csc_status": (csculpt.Status, "CSC_"),
                 "csc_linearisation": (csculpt.Linearisation, "CSC_LINEARISATION_"),
                 "csc_merge_method": (csculpt.MergeMethod, "CSC_MERGE_"),
                 "csc_event_kind": (csculpt.EventKind, "CSC_EVENT_"),
                 "csc_peer_state": (csculpt.PeerState, "CSC_PEER_")}
        found = re.findall(r"typedef enum (csc_\w+) \{(.*?)\}", text, flags=re.S)
        self.assertEqual(sorted(name for name, _ in found), sorted(enums))
        for name, body in found:
            mirror, prefix = enums[name]
            values = {k[len(prefix):]: int(v, 0)
                      for k, v in re.findall(r"(CSC_\w+)\s*=\s*(0x[0-9A-Fa-f]+|\d+)", body)}
            with self.subTest(enum=name):
                self.assertEqual({m.name: int(m) for m in mirror}, values)

    def test_merge_method_names_round_trip(self):
        names = csculpt.merge_method_names()
        self.assertEqual(names["full"], csculpt.MergeMethod.FULL)
        self.assertEqual(len(names), 10)
        for name, method in names.items():
            self.assertEqual(csculpt._merge_method(name), method)

    def test_status_strings(self):
        self.assertEqual(csculpt.status_str(csculpt.Status.ERROR_IO), "input/output error")
        self.assertEqual(csculpt.status_str(1234), "unknown status")


def import_module_file(path, environ=None):
    """Imports the file at `path` as a fresh module, as `import csculpt` would, with os.environ
    temporarily replaced by `environ`."""
    saved = dict(os.environ)
    name = f"csculpt_under_test_{next(_counter)}"
    try:
        if environ is not None:
            os.environ.clear()
            os.environ.update(environ)
        spec = importlib.util.spec_from_file_location(name, path)
        module = importlib.util.module_from_spec(spec)
        sys.modules[name] = module  # dataclasses look their module up while it executes
        spec.loader.exec_module(module)
        return module
    finally:
        sys.modules.pop(name, None)
        os.environ.clear()
        os.environ.update(saved)


_counter = itertools.count()


class Version(unittest.TestCase):

    def setUp(self):
        with open(csculpt.__file__, encoding="utf-8") as f:
            self.source = f.read()

    def test_the_library_is_the_version_this_module_expects(self):
        major, minor, patch = csculpt.version()
        self.assertEqual(major, csculpt.EXPECTED_VERSION[0])
        self.assertGreaterEqual(minor, csculpt.EXPECTED_VERSION[1])
        self.assertEqual(csculpt.version_string(), f"{major}.{minor}.{patch}")
        self.assertGreaterEqual(csculpt.wire_protocol_version(), 1)

    def test_check_version_accepts_same_major_and_newer_minor(self):
        self.assertEqual(csculpt.check_version(200, "0.2.0", (0, 2)), (0, 2, 0))
        self.assertEqual(csculpt.check_version(501, "0.5.1", (0, 2)), (0, 5, 1))
        self.assertEqual(csculpt.check_version(10203, "1.2.3", (1, 0)), (1, 2, 3))

    def test_check_version_refuses_an_older_minor_naming_both_versions(self):
        with self.assertRaises(ImportError) as ctx:
            csculpt.check_version(200, "0.2.0", (0, 3))
        self.assertIn("0.2.0", str(ctx.exception))
        self.assertIn("0.3", str(ctx.exception))

    def test_check_version_refuses_another_major(self):
        for number, string, expected in [(10200, "1.2.0", (0, 2)), (200, "0.2.0", (1, 0))]:
            with self.subTest(library=string, expected=expected):
                with self.assertRaisesRegex(ImportError, re.escape(string)):
                    csculpt.check_version(number, string, expected)

    def test_check_version_refuses_a_string_that_disagrees_with_the_number(self):
        with self.assertRaisesRegex(ImportError, "version string '0.3.0'"):
            csculpt.check_version(200, "0.3.0", (0, 2))

    def test_importing_with_a_higher_expected_minor_raises_import_error(self):
        lib = csculpt.version()
        patched = self.source.replace("EXPECTED_VERSION = (0, 5)",
                                      f"EXPECTED_VERSION = ({lib[0]}, {lib[1] + 1})")
        self.assertNotEqual(patched, self.source, "EXPECTED_VERSION line not found")
        with tempfile.TemporaryDirectory() as tmp, self.assertRaises(ImportError) as ctx:
            path = os.path.join(tmp, "csculpt.py")
            with open(path, "w", encoding="utf-8") as f:
                f.write(patched)
            import_module_file(path)
        message = str(ctx.exception)
        self.assertIn(csculpt.version_string(), message)
        self.assertIn(f"{lib[0]}.{lib[1] + 1}", message)

    def test_monkeypatched_expected_version_fails_the_load(self):
        saved = csculpt.EXPECTED_VERSION
        try:
            csculpt.EXPECTED_VERSION = (saved[0], 99)
            with self.assertRaisesRegex(ImportError, "needs 0.99"):
                csculpt._load()
        finally:
            csculpt.EXPECTED_VERSION = saved
        lib, path = csculpt._load()  # and the real expectation still loads
        self.assertEqual(path, csculpt.library_path)

    def test_an_explicit_library_that_cannot_load_is_an_import_error(self):
        env = dict(os.environ, CSCULPT_LIBRARY="/nonexistent/libcsculpt.so.0")
        with self.assertRaisesRegex(ImportError, "/nonexistent/libcsculpt.so.0"):
            import_module_file(csculpt.__file__, env)

    def test_finds_the_library_beside_the_module(self):
        with tempfile.TemporaryDirectory() as tmp:
            module_path = os.path.join(tmp, "csculpt.py")
            shutil.copy(csculpt.__file__, module_path)
            os.symlink(csculpt.library_path, os.path.join(tmp, "libcsculpt.so.0"))
            env = {k: v for k, v in os.environ.items() if k != "CSCULPT_LIBRARY"}
            module = import_module_file(module_path, env)
            self.assertEqual(module.library_path, os.path.join(tmp, "libcsculpt.so.0"))
            self.assertEqual(module.version(), csculpt.version())


if __name__ == "__main__":
    unittest.main()
