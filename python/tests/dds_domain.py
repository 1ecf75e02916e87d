"""DDS domains for tests on loopback that no other test process on this machine uses at once.

The same locks as tests/support/dds_domain.hpp (one file per domain, an advisory lock the kernel
drops when the process exits), so Python and C++ tests running in parallel never meet in one
domain and mix their sites' samples.
"""

import fcntl
import os

FIRST_DOMAIN = 100
DOMAINS = 120
LOCK_PREFIX = "/tmp/hapticd-test-dds-domain-"

_held = []  # the open lock files: closing one would drop its lock


def unique_dds_domain():
    """A domain from 100 to 219 that no other process holds, held until this one exits."""
    for domain in range(FIRST_DOMAIN, FIRST_DOMAIN + DOMAINS):
        try:
            fd = os.open(f"{LOCK_PREFIX}{domain}.lock", os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        except OSError:  # another user's lock file, say
            continue
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            os.close(fd)
            continue
        _held.append(fd)
        return domain
    raise RuntimeError(f"no free DDS domain for a test: all of {LOCK_PREFIX}100…219.lock are held")
