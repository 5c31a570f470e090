#!/usr/bin/env python3
"""Checks that includes point down the layers: every uhaptics header a source file includes belongs
to the file's own layer or a lower one. Layers, bottom up: core, models, protocol, backends,
renderers, chai3d, tools/examples. A file's layer comes from its folder (a device folder's layer
sub-folders: model, backend, renderer, chai3d, servo, examples); an included header's from its include path
(uhaptics/<layer>/...). Usage: check_layers.py <source root>; exits 1 listing each violation."""
import os
import re
import sys

ORDER = {"core": 1, "models": 2, "protocol": 3, "backends": 4, "renderers": 5, "chai3d": 6, "tools": 7, "experiments": 7}
# Folder (relative to the root) -> layer; the longest matching prefix wins.
FOLDERS = {
    "plugin/core": "core", "devices/models": "models", "devices/protocol": "protocol",
    "devices/backends": "backends", "plugin/renderers": "renderers", "plugin/chai3d": "chai3d",
    "tools": "tools", "examples": "tools",
}
DEVICE_LAYERS = {"model": "models", "backend": "backends", "renderer": "renderers", "chai3d": "chai3d", "servo": "tools",
                 "examples": "tools"}
INCLUDE = re.compile(r'^\s*#\s*include\s+"uhaptics/([a-z0-9_]+)/')


def layer_of(path):
    parts = path.split("/")
    if len(parts) > 3 and parts[0] == "devices" and parts[2] in DEVICE_LAYERS:
        return DEVICE_LAYERS[parts[2]]
    best = None
    for prefix, layer in FOLDERS.items():
        if path.startswith(prefix + "/") and (best is None or len(prefix) > len(best[0])):
            best = (prefix, layer)
    return best[1] if best else None


def main():
    root = sys.argv[1] if len(sys.argv) > 1 else "."
    violations, files = [], 0
    for top in ("plugin", "devices", "tools", "examples"):
        for folder, _, names in os.walk(os.path.join(root, top)):
            for name in names:
                if not name.endswith((".hpp", ".cpp", ".h")):
                    continue
                path = os.path.relpath(os.path.join(folder, name), root)
                layer = layer_of(path)
                if layer is None:
                    continue
                files += 1
                with open(os.path.join(root, path), encoding="utf-8") as f:
                    for number, line in enumerate(f, 1):
                        m = INCLUDE.match(line)
                        if m and m.group(1) in ORDER and ORDER[m.group(1)] > ORDER[layer]:
                            violations.append(f"{path}:{number}: {layer} includes uhaptics/{m.group(1)}/ (a higher layer)")
    for v in violations:
        print(v)
    print(f"check_layers: {files} files, {len(violations)} includes against the layer order")
    return 1 if violations else 0


if __name__ == "__main__":
    sys.exit(main())
