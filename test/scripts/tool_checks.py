"""Shared by the script tests that run the built tools and count their checks: the build's tool
directory (HAMERITT_BIN_DIR), the source tree (HAMERITT_SOURCE_DIR), the tools' environment
(the checkout's config/), check() with its counts, and run() of a built tool."""

import os
import subprocess

BIN = os.environ["HAMERITT_BIN_DIR"]
SRC = os.environ["HAMERITT_SOURCE_DIR"]
ENV = dict(os.environ, HAMERITT_CONFIG_DIR=os.path.join(SRC, "config"))


class Counts:
    passed = 0
    failed = 0

    def summary(self):
        """The closing line, "N passed, N failed"."""
        return "%d passed, %d failed" % (self.passed, self.failed)


counts = Counts()


def check(cond, name, why=""):
    if cond:
        counts.passed += 1
    else:
        counts.failed += 1
        print("FAIL %s %s" % (name, why))


def run(*args):
    """A built tool (args[0], in BIN) with its arguments; its CompletedProcess, output as text."""
    return subprocess.run([os.path.join(BIN, args[0])] + list(args[1:]), env=ENV,
                          capture_output=True, text=True)
