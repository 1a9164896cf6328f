#!/usr/bin/env python3
"""Enforces the layering of DESIGN.md section 8 on the source tree (a test; exit 1 on a violation).

Two kinds of arrows are checked:
  * package -> package: every `find_package(<workspace package>)` in a CMakeLists.txt and every
    `#include "<workspace package>/..."` must point to a package on a lower floor, or to a
    framework package (src/) from a capability (packages/) only through node code;
  * core code (a package's include/ and src/, except node adapters) never includes the node
    runtime, the launch library, the introspection library, message types or Fast DDS: cores stay
    embeddable in-process (the gym environment, data generation) and testable without DDS.

Usage: check_layering.py WORKSPACE_ROOT [--graph]   (--graph prints the package graph)
"""
import os
import re
import sys

# Floors (DESIGN.md section 8). Arrows point down only; the same floor is not allowed either,
# except the listed pairs (floor-2 packages are independent of each other today).
FLOORS = {
    # floor 0: interfaces, the CMake helpers, the DDS-free common floor
    "ros2_msgs": 0, "unav_msgs": 0, "unav_common": 0,
    # floor 1: the node kit and message introspection (framework)
    "unav_runtime": 1, "unav_introspection": 1, "unav_launch": 1,
    # floor 2 (framework): rosbag2 storage over the introspection types
    "unav_bag": 2,
    # floor 2: physics model, scene description (no GL)
    "unav_physics": 2, "unav_scene": 2,
    # floor 3: capabilities (DDS-free cores + their thin nodes)
    "unav_renderer": 3, "unav_control": 3, "unav_localization": 3, "unav_evaluation": 3,
    "unav_datagen": 3, "unav_autopilot": 3,
    # floor 4: in-process composition of capabilities (episode, environment core)
    "unav_sim": 4,
    # floor 5: what embeds the composition: the Gymnasium binding, the planners (whose tests fly
    # them in the environment core)
    "unav_gym": 5, "unav_planning": 5,
    # floor 6: tools, launch, resources, examples, system tests
    "unav_cli": 6, "unav_examples": 6, "unav_resources": 6,
    "unav_system_tests": 6, "unav_fuzz": 6,
}
# Allowed arrows within one floor (a capability reusing another's DDS-free core).
# The plant builder of a scenario (unav_physics_scenario: the world's seabed and current) and the
# physics server node read the scene through unav_scene; the physics model (target unav_physics)
# links only unav_common.
SAME_FLOOR_OK = {("unav_physics", "unav_scene")}
# Known violations being removed, printed as warnings with what removes them. Do not add to this
# list: fix the arrow instead.
PENDING = {}
# Framework packages (src/) never depend on capabilities (packages/): `unav eval` dispatches to
# the evaluation package's executable instead of linking it.
FRAMEWORK = {"unav_runtime", "unav_introspection", "unav_launch", "unav_bag", "unav_cli", "unav_examples", "unav_common",
             "unav_cmake", "unav_resources"}
CAPABILITIES = {"unav_physics", "unav_scene", "unav_renderer", "unav_control", "unav_localization",
                "unav_evaluation", "unav_datagen", "unav_sim", "unav_gym", "unav_planning", "unav_autopilot"}
# Headers a DDS-free core must never include.
FORBIDDEN_IN_CORE = re.compile(
    r'#\s*include\s*[<"](unav_runtime/|unav_launch/|unav_introspection/|fastdds/|fastrtps/|fastcdr/|'
    r'[a-z0-9_]+_msgs/msg/)')
INCLUDE = re.compile(r'^\s*#\s*include\s*[<"]([a-z0-9_]+)/', re.M)
FIND_PACKAGE = re.compile(r'find_package\(\s*([A-Za-z0-9_]+)')


def is_node_file(rel):
    """Node adapters, tools, tests and benchmarks may use the runtime; core files may not."""
    parts = rel.split(os.sep)
    if parts[0] in ("nodes", "test", "tests", "bench", "tools"):
        return True
    base = parts[-1]
    return base.endswith("_node.cpp") or base.endswith("_node.hpp") or base.endswith("_main.cpp")


def packages(root):
    out = {}
    for top in ("interfaces", "src", "packages", "tests"):
        d = os.path.join(root, top)
        if not os.path.isdir(d):
            continue
        for name in sorted(os.listdir(d)):
            p = os.path.join(d, name)
            if os.path.isfile(os.path.join(p, "CMakeLists.txt")):
                out[name] = p
    return out


def include_target(token):
    """Workspace package owning an include prefix ("sensor_msgs" belongs to ros2_msgs)."""
    if token in FLOORS:
        return token
    if token.endswith("_msgs") or token in ("builtin_interfaces", "rosgraph_msgs", "rmw_dds_common"):
        return "ros2_msgs"
    return None


def main():
    root = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else ".")
    pkgs = packages(root)
    errors = []
    for name in pkgs:
        if name not in FLOORS and name != "unav_cmake":
            errors.append(f"{name}: package has no floor in check_layering.py (add it, DESIGN.md section 8)")
    edges = {}  # src -> dst -> (kind, where); kind "core" wins over "node" over "test"
    rank = {"core": 0, "node": 1, "test": 2}

    def arrow(src, dst, kind, where):
        if dst is None or dst == src or src not in FLOORS:
            return
        old = edges.setdefault(src, {}).get(dst)
        if old is None or rank[kind] < rank[old[0]]:
            edges[src][dst] = (kind, where)

    for name, path in pkgs.items():
        if name not in FLOORS:
            continue
        for dirpath, _, files in os.walk(path):
            for fn in files:
                if not fn.endswith((".hpp", ".h", ".cpp", ".cc")):
                    continue
                full = os.path.join(dirpath, fn)
                rel = os.path.relpath(full, path)
                top = rel.split(os.sep)[0]
                kind = "test" if top in ("test", "bench", "tools") else ("node" if is_node_file(rel) else "core")
                with open(full, errors="replace") as f:
                    text = f.read()
                for m in INCLUDE.finditer(text):
                    arrow(name, include_target(m.group(1)), kind, rel)
                if name in CAPABILITIES and kind == "core":
                    for line in text.splitlines():
                        if FORBIDDEN_IN_CORE.match(line.strip()):
                            errors.append(f"{name}/{rel}: core code includes '{line.strip()}' "
                                          "(cores are DDS-free; move it into the node adapter)")
        # A workspace package found by CMake but never included is linked for nothing (or only
        # for a path/YAML helper that belongs on the common floor).
        with open(os.path.join(path, "CMakeLists.txt")) as f:
            for m in FIND_PACKAGE.finditer(f.read()):
                dep = m.group(1)
                if dep in FLOORS and dep != name and dep not in edges.get(name, {}) and dep not in (
                        "ros2_msgs", "unav_msgs", "unav_resources"):
                    errors.append(f"{name}: find_package({dep}) but no file includes it")
    for src, dsts in sorted(edges.items()):
        for dst, (kind, where) in sorted(dsts.items()):
            fs, fd = FLOORS[src], FLOORS[dst]
            if (src, dst) in PENDING:
                print(f"layering: warning: {src} -> {dst} ({where}): pending: {PENDING[(src, dst)]}")
            elif src in CAPABILITIES and dst == "unav_launch":
                errors.append(f"{src} -> unav_launch ({where}): capabilities find resources through unav_common, "
                              "not the launch library")
            elif src in FRAMEWORK and dst in CAPABILITIES:
                errors.append(f"{src} -> {dst} ({where}): the framework depends on a capability")
            elif fd > fs or (fd == fs and kind != "test" and (src, dst) not in SAME_FLOOR_OK):
                errors.append(f"{src} (floor {fs}) -> {dst} (floor {fd}) ({kind}: {where}): arrows must point down")
    if "--graph" in sys.argv:
        for src, dsts in sorted(edges.items()):
            print(f"{src} (floor {FLOORS.get(src)}) -> " +
                  ", ".join(f"{d}[{k}]" for d, (k, _) in sorted(dsts.items())))
    for e in errors:
        print("layering: " + e)
    print(f"layering: {len(pkgs)} packages, {sum(len(d) for d in edges.values())} arrows, {len(errors)} violations")
    return 1 if errors else 0


if __name__ == "__main__":
    sys.exit(main())
