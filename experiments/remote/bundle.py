#!/usr/bin/env python3
"""Bundle a built bvhlab with the shared libraries it loads, for a Linux machine that lacks Debian's
packages (a GPU node of another distribution, a container image): experiments/remote/README.md.

    python3 experiments/remote/bundle.py --out DIR [--binary build/bvhlab] [--tar FILE.tar.xz]

DIR gets bvhlab and lib/; run it as  LD_LIBRARY_PATH=DIR/lib DIR/bvhlab ...  The C and C++ runtimes are
not bundled (any newer glibc/libstdc++ runs a Debian 12 build). Libraries the GPU path never uses are
replaced by stubs (--stub; the default list below), which cuts the closure from ~580 MB to ~85 MB:
OSMesa (and LLVM behind it: the GPU path is EGL) and the codecs OpenImageIO links for formats bvhlab
never reads (video, DICOM, OpenVDB, camera raw, HEIF, OpenCV). A stub has the library's soname, defines
each symbol the bundle imports from it under the same version, and depends on nothing; each function
returns at once a pointer to 256 zero bytes, so the version queries OpenImageIO makes while it catalogs
its plugins (some from static constructors) read an empty string. Nothing else in a stub may be called.
"""
import argparse
import os
import re
import shutil
import subprocess
import sys
import tarfile
import tempfile

# The C/C++ runtime and the loader: the target machine's own (newer ones run this build).
RUNTIME = {"libc.so.6", "libm.so.6", "libpthread.so.0", "libdl.so.2", "librt.so.1", "libutil.so.1",
           "ld-linux-x86-64.so.2", "libstdc++.so.6", "libgcc_s.so.1", "libresolv.so.2"}

DEFAULT_STUBS = [
    "libOSMesa.so.8",                                                    # --backend osmesa only
    "libopencv_core.so.406", "libopencv_imgproc.so.406", "libopencv_videoio.so.406",
    "libdcmimage.so.17", "libdcmimgle.so.17", "libdcmdata.so.17", "liboflog.so.17", "libofstd.so.17",
    "libavcodec.so.59", "libavformat.so.59", "libavutil.so.57", "libswscale.so.6",
    "libheif.so.1", "libopenvdb.so.10.0", "libraw_r.so.20",
]


def run(cmd):
    return subprocess.run(cmd, capture_output=True, text=True, check=True).stdout


def library_paths():
    """soname -> path, from the loader's cache (x86-64 entries, first wins as for ld.so)."""
    paths = {}
    for line in run(["ldconfig", "-p"]).splitlines()[1:]:
        m = re.match(r"\s*(\S+) \((.*?)\) => (\S+)", line)
        if m and "x86-64" in m.group(2):
            paths.setdefault(m.group(1), m.group(3))
    return paths


def needed(path):
    return re.findall(r"\(NEEDED\)\s+Shared library: \[(.*?)\]", run(["readelf", "-d", path]))


def dynamic_symbols(path):
    """(name, version or None, default version?, type, size, defined?) for each .dynsym entry."""
    for line in run(["readelf", "--dyn-syms", "-W", path]).splitlines():
        f = line.split()
        if len(f) < 8 or not f[0][:-1].isdigit():
            continue
        name, version, default = f[7], None, True
        if "@@" in name:
            name, version = name.split("@@", 1)
        elif "@" in name:
            name, version = name.split("@", 1)
            default = False
        yield name, version, default, f[3], int(f[2], 16) if f[2].startswith("0x") else int(f[2]), \
            f[6] not in ("UND", "ABS"), f[4]


def closure(binary, stubs, paths):
    """The libraries to copy, and the stubbed sonames something in the closure needs."""
    seen, todo, kept, stubbed = set(), [binary], [], set()
    while todo:
        for soname in needed(todo.pop()):
            if soname in seen or soname in RUNTIME:
                continue
            seen.add(soname)
            if soname in stubs:
                stubbed.add(soname)
                continue
            if soname not in paths:
                sys.exit(f"bundle: {soname} (needed by the closure of {binary}) is not in ldconfig's cache")
            kept.append(soname)
            todo.append(paths[soname])
    return kept, stubbed


def write_stub(soname, source, wanted, outdir, workdir):
    asm = [".bss", ".balign 64", "__stub_zeros: .zero 256", ".text"]
    versions = set()
    for i, (name, version, default, kind, size, defined, bind) in enumerate(dynamic_symbols(source)):
        if not defined or bind not in ("GLOBAL", "WEAK") or name == version or name not in wanted:
            continue
        label = f"__stub_{i}"
        if kind == "OBJECT":
            asm += [".bss", f".type {label},@object", f".size {label},{max(size, 1)}",
                    f"{label}: .zero {max(size, 1)}", ".text"]
        elif kind == "TLS":
            asm += ['.section .tbss,"awT",@nobits', f".type {label},@tls_object",
                    f".size {label},{max(size, 1)}", f"{label}: .zero {max(size, 1)}", ".text"]
        else:
            asm += [f".type {label},@function", f"{label}: leaq __stub_zeros(%rip), %rax; ret"]
        if version:
            versions.add(version)
            asm += [f".globl {label}", f'.symver {label}, "{name}@{"@" if default else ""}{version}"']
        else:
            asm += [f'.globl "{name}"', f'.set "{name}", {label}']
    src = os.path.join(workdir, soname + ".s")
    script = os.path.join(workdir, soname + ".map")
    with open(src, "w") as f:
        f.write("\n".join(asm) + "\n")
    with open(script, "w") as f:
        f.write("".join(f"{v} {{ global: *; }};\n" for v in sorted(versions)) or "{ global: *; };\n")
    subprocess.run(["cc", "-shared", "-nostdlib", "-o", os.path.join(outdir, soname),
                    "-Wl,-soname," + soname, "-Wl,--version-script," + script, src], check=True)


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--binary", default="build/bvhlab", help="the executable to bundle (default build/bvhlab)")
    ap.add_argument("--out", required=True, help="output folder: bvhlab and lib/ (replaced)")
    ap.add_argument("--stub", action="append", metavar="SONAME",
                    help="replace this library by a stub (repeatable; default: OSMesa and OpenImageIO's unused codecs)")
    ap.add_argument("--no-stubs", action="store_true", help="copy the whole closure (~580 MB)")
    ap.add_argument("--tar", metavar="FILE.tar.xz", help="also write the folder as one xz archive")
    args = ap.parse_args()
    if not os.path.isfile(args.binary):
        sys.exit(f"bundle: {args.binary}: no such executable (build first: bash setup.sh build)")
    stubs = set() if args.no_stubs else set(args.stub or DEFAULT_STUBS)
    paths = library_paths()
    kept, stubbed = closure(args.binary, stubs, paths)
    lib = os.path.join(args.out, "lib")
    shutil.rmtree(args.out, ignore_errors=True)
    os.makedirs(lib)
    shutil.copy2(args.binary, os.path.join(args.out, "bvhlab"))
    for soname in kept:
        shutil.copy2(paths[soname], os.path.join(lib, soname))
    wanted = set()
    for obj in [args.binary] + [paths[s] for s in kept]:
        wanted.update(name for name, _, _, _, _, defined, _ in dynamic_symbols(obj) if not defined)
    with tempfile.TemporaryDirectory() as work:
        for soname in sorted(stubbed):
            write_stub(soname, paths[soname], wanted, lib, work)
    size = sum(os.path.getsize(os.path.join(lib, f)) for f in os.listdir(lib))
    print(f"bundle: {args.out}: {len(kept)} libraries copied, {len(stubbed)} stubbed, "
          f"{size / 2**20:.1f} MiB in lib/")
    if args.tar:
        with tarfile.open(args.tar, "w:xz", preset=6) as tar:
            tar.add(args.out, arcname=".")
        print(f"bundle: wrote {args.tar} ({os.path.getsize(args.tar) / 2**20:.1f} MiB)")


if __name__ == "__main__":
    main()
