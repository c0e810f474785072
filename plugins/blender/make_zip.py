#!/usr/bin/env python3
"""Builds the Blender add-on zip: the csculpt_blender package with the ctypes binding
(csculpt.py), libcsculpt.so.0 beside it and, in lib/, every shared library it needs that is
not part of glibc, libstdc++ or libgcc (libzmq, libsodium, libpgm, libnorm, the Kerberos
libraries libzmq links, libbsd, ...). The copies get RUNPATH $ORIGIN (libcsculpt: $ORIGIN/lib)
with patchelf, so they find each other on a machine that has only Blender.

    make_zip.py --library build/capi/libcsculpt.so.0 --binding capi/python/csculpt.py \
                --package plugins/blender/csculpt_blender --readme plugins/blender/README.md \
                --out build/plugins/blender/csculpt_blender.zip
"""

import argparse
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile

PACKAGE = "csculpt_blender"
SONAME = "libcsculpt.so.0"
# Always on the target: the C runtime and the C++ runtime Blender itself links.
SYSTEM = re.compile(r"^(linux-vdso|ld-linux.*|libc|libm|libdl|librt|libpthread|libresolv|"
                    r"libstdc\+\+|libgcc_s)\.so")


def dependencies(library):
    """{soname: path} of everything `library` loads (ldd: the whole closure)."""
    out = subprocess.run(["ldd", library], check=True, capture_output=True, text=True).stdout
    deps = {}
    for line in out.splitlines():
        m = re.match(r"\s*(\S+) => (\S+)", line)
        if m and m.group(2) != "not" and not SYSTEM.match(m.group(1)):
            deps[m.group(1)] = m.group(2)
        elif m and m.group(2) == "not":
            sys.exit(f"make_zip: {library} needs {m.group(1)}, which is not found")
    return deps


def patchelf(*args):
    tool = shutil.which("patchelf")
    if tool is None:
        sys.exit("make_zip: patchelf is needed to set $ORIGIN in the bundled libraries "
                 "(apt-get install patchelf)")
    subprocess.run([tool, *args], check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--library", required=True)
    ap.add_argument("--binding", required=True)
    ap.add_argument("--package", required=True)
    ap.add_argument("--readme")
    ap.add_argument("--out", required=True)
    a = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        root = os.path.join(tmp, PACKAGE)
        lib = os.path.join(root, "lib")
        os.makedirs(lib)
        for name in sorted(os.listdir(a.package)):
            if name.endswith(".py"):
                shutil.copyfile(os.path.join(a.package, name), os.path.join(root, name))
        shutil.copyfile(a.binding, os.path.join(root, "csculpt.py"))
        if a.readme:
            shutil.copyfile(a.readme, os.path.join(root, "README.md"))
        target = os.path.join(root, SONAME)
        shutil.copyfile(a.library, target)
        if shutil.which("strip"):
            # Debug information is most of a RelWithDebInfo library: artists do not need it.
            subprocess.run(["strip", "--strip-debug", target], check=True)
        patchelf("--set-rpath", "$ORIGIN/lib", target)
        for soname, path in sorted(dependencies(a.library).items()):
            copy = os.path.join(lib, soname)
            shutil.copyfile(path, copy)
            os.chmod(copy, 0o755)
            patchelf("--set-rpath", "$ORIGIN", copy)
        os.makedirs(os.path.dirname(os.path.abspath(a.out)), exist_ok=True)
        partial = a.out + ".part"
        with zipfile.ZipFile(partial, "w", zipfile.ZIP_DEFLATED) as z:
            for dirpath, dirnames, filenames in os.walk(root):
                dirnames.sort()
                for f in sorted(filenames):
                    full = os.path.join(dirpath, f)
                    info = zipfile.ZipInfo(os.path.relpath(full, tmp), (2020, 1, 1, 0, 0, 0))
                    info.external_attr = (os.stat(full).st_mode & 0o777) << 16
                    info.compress_type = zipfile.ZIP_DEFLATED
                    with open(full, "rb") as fh:
                        z.writestr(info, fh.read())
        os.replace(partial, a.out)


if __name__ == "__main__":
    main()
