"""The docs cannot rot: every fenced block marked ```bash runnable in README.md and docs/*.md is
run, line by line (a trailing backslash joins lines; comments and blank lines skipped), from the
repository root with the workspace's environment, a fresh $HOME and a time limit, and must exit 0.
Prints one line per command and the count; exit 1 on the first failure, with its output."""
import glob
import os
import re
import subprocess
import sys
import tempfile
import time


def runnable_commands(path):
    text = open(path, encoding="utf-8").read()
    for m in re.finditer(r"^```bash runnable[^\n]*\n(.*?)^```", text, re.S | re.M):
        pending = ""
        for raw in m.group(1).split("\n"):
            line = raw.rstrip()
            if pending:
                line = pending + " " + line.lstrip()
                pending = ""
            if line.endswith("\\"):
                pending = line[:-1]
                continue
            if line.strip() and not line.lstrip().startswith("#"):
                yield line.strip()


def main(ws):
    pages = [os.path.join(ws, "README.md")] + sorted(glob.glob(os.path.join(ws, "docs", "*.md")))
    home = tempfile.mkdtemp(prefix="unav_docs_home_")
    env = dict(os.environ, HOME=home, UNAV_RESOURCE_PATH=ws)
    run = 0
    for page in pages:
        for cmd in runnable_commands(page):
            t0 = time.monotonic()
            p = subprocess.run(["bash", "-c", f"set -eo pipefail; source install/setup.bash; {cmd}"], cwd=ws, env=env,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=600)
            rel = os.path.relpath(page, ws)
            if p.returncode != 0:
                print(f"FAIL: {rel}: `{cmd}` exited {p.returncode}\n--- output (tail):\n" + "\n".join(p.stdout.splitlines()[-30:]))
                return 1
            run += 1
            print(f"ok ({time.monotonic() - t0:5.1f} s) {rel}: {cmd}")
    if run == 0:
        print("FAIL: no ```bash runnable block found")
        return 1
    print(f"docs: {run} commands run from {len(pages)} pages, all exit 0")
    return 0


if __name__ == "__main__":
    sys.exit(main(os.path.abspath(sys.argv[1])))
