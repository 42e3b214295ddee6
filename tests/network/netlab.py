"""Hosts on one machine for network tests: network namespaces joined by veths, a bridge or a router.

Only usable under tests/network/lab-run, which gives the test its own network and mount
namespaces: whatever a Lab builds is invisible to the host and vanishes with the test.

    with Lab("routed", netem="delay 50ms loss 1%") as lab:
        gateway = lab.spawn("vehicle", ["teejet-gateway", ...], log="gateway.log")
        listing = lab.run("bench", ["valvectl", ...], timeout=30)

Topologies (addresses from the documentation ranges only, RFC 5737):
  bridged  vehicle 192.0.2.2, bench 192.0.2.3, bench2 192.0.2.4 on one bridge: one L2 segment,
           so multicast discovery works.
  routed   vehicle 192.0.2.2/24 -- router 192.0.2.1 | 198.51.100.1 -- bench 198.51.100.2/24 and
           bench2 198.51.100.3 on a bridge behind the router; multicast does not cross it.
netem (routed only) is applied to every interface the router sends on, so each direction of the
vehicle-bench path gets it once. The host kernel has no sch_netem: use lab-run --uml.

Every host has its own /dev/shm: Fast DDS would otherwise carry data between "hosts" through
shared memory and never touch the network under test.
"""

import os
import shlex
import signal
import subprocess

SKIP = 77  # CTest's SKIP_RETURN_CODE for the network tests

TOPOLOGIES = {
    "bridged": {"vehicle": "192.0.2.2", "bench": "192.0.2.3", "bench2": "192.0.2.4"},
    "routed": {"vehicle": "192.0.2.2", "router": "192.0.2.1", "bench": "198.51.100.2",
               "bench2": "198.51.100.3"},
}
ROUTER_BENCH_SIDE = "198.51.100.1"


class LabUnavailable(Exception):
    """The machine cannot build this lab (e.g. no sch_netem on the host): the test is skipped."""


def _sh(*argv, check=True):
    result = subprocess.run(argv, capture_output=True, text=True)
    if check and result.returncode != 0:
        raise RuntimeError(f"netlab: `{shlex.join(argv)}` failed ({result.returncode}): "
                           f"{result.stderr.strip()}")
    return result


class Lab:
    def __init__(self, topology, netem=None):
        if os.environ.get("NETLAB_PRIVATE") != "1":
            raise RuntimeError("netlab: run the test under tests/network/lab-run, which keeps "
                               "its namespaces away from the host's interfaces")
        if topology not in TOPOLOGIES:
            raise ValueError(f"netlab: unknown topology {topology!r}; one of {sorted(TOPOLOGIES)}")
        if netem and topology != "routed":
            raise ValueError("netlab: netem is applied by the router: use the routed topology")
        self.topology = topology
        self.netem = netem
        self._processes = []

    def address(self, host):
        return TOPOLOGIES[self.topology][host]

    @property
    def hosts(self):
        return [h for h in TOPOLOGIES[self.topology] if h != "router"]

    def __enter__(self):
        try:
            self._build()
        except BaseException:
            self._teardown()
            raise
        return self

    def __exit__(self, *exc):
        self._teardown()
        return False

    def _add_host(self, name):
        _sh("ip", "netns", "add", name)
        _sh("ip", "-n", name, "link", "set", "lo", "up")
        os.makedirs(f"/run/netlab/{name}/shm", exist_ok=True)
        _sh("mount", "-t", "tmpfs", "-o", "mode=1777", f"shm-{name}", f"/run/netlab/{name}/shm")

    def _veth_into(self, host, address_with_prefix, outer_name, outer_netns=None):
        """A veth with its `eth0` end in HOST; the other end stays here or goes to OUTER_NETNS."""
        _sh("ip", "link", "add", outer_name, "type", "veth", "peer", "name", "eth0", "netns", host)
        if outer_netns:
            _sh("ip", "link", "set", outer_name, "netns", outer_netns)
        _sh("ip", "-n", host, "addr", "add", address_with_prefix, "dev", "eth0")
        _sh("ip", "-n", host, "link", "set", "eth0", "up")

    def _build(self):
        addresses = TOPOLOGIES[self.topology]
        if self.topology == "bridged":
            _sh("ip", "link", "add", "br0", "type", "bridge")
            # No IGMP querier here: snooping would decide by reports nobody asks for.
            _sh("ip", "link", "set", "br0", "type", "bridge", "mcast_snooping", "0")
            _sh("ip", "link", "set", "br0", "up")
            for host, address in addresses.items():
                self._add_host(host)
                self._veth_into(host, f"{address}/24", f"p-{host}")
                _sh("ip", "link", "set", f"p-{host}", "master", "br0", "up")
                # Multicast needs a route; there is no gateway on a bare segment.
                _sh("ip", "-n", host, "route", "add", "224.0.0.0/4", "dev", "eth0")
            return

        self._add_host("router")
        _sh("ip", "netns", "exec", "router", "sysctl", "-qw", "net.ipv4.ip_forward=1")
        self._add_host("vehicle")
        self._veth_into("vehicle", f"{addresses['vehicle']}/24", "r-vehicle", "router")
        _sh("ip", "-n", "router", "addr", "add", f"{addresses['router']}/24", "dev", "r-vehicle")
        _sh("ip", "-n", "router", "link", "set", "r-vehicle", "up")
        _sh("ip", "-n", "vehicle", "route", "add", "default", "via", addresses["router"])
        _sh("ip", "-n", "router", "link", "add", "br-bench", "type", "bridge")
        _sh("ip", "-n", "router", "link", "set", "br-bench", "type", "bridge", "mcast_snooping", "0")
        _sh("ip", "-n", "router", "addr", "add", f"{ROUTER_BENCH_SIDE}/24", "dev", "br-bench")
        _sh("ip", "-n", "router", "link", "set", "br-bench", "up")
        for host in ("bench", "bench2"):
            self._add_host(host)
            self._veth_into(host, f"{addresses[host]}/24", f"p-{host}", "router")
            _sh("ip", "-n", "router", "link", "set", f"p-{host}", "master", "br-bench", "up")
            _sh("ip", "-n", host, "route", "add", "default", "via", ROUTER_BENCH_SIDE)
        if self.netem:
            # Every interface the router transmits on towards a host: each direction once.
            for device in ("r-vehicle", "p-bench", "p-bench2"):
                result = _sh("ip", "netns", "exec", "router", "tc", "qdisc", "add", "dev", device,
                             "root", "netem", *self.netem.split(), check=False)
                if result.returncode != 0:
                    raise LabUnavailable(f"tc netem is not available here ({result.stderr.strip()}); "
                                         "run under tests/network/lab-run --uml")

    def _wrap(self, host, argv):
        if host not in TOPOLOGIES[self.topology]:
            raise ValueError(f"netlab: no host {host!r} in the {self.topology} lab")
        # ip netns exec gives the command its own mount namespace: the host's /dev/shm goes there.
        return ["ip", "netns", "exec", host, "sh", "-c",
                'mount --bind "$0" /dev/shm && exec "$@"', f"/run/netlab/{host}/shm", *argv]

    def spawn(self, host, argv, env=None, log=None):
        """Start ARGV on HOST; it is stopped (SIGTERM, then SIGKILL after 5 s) when the lab ends."""
        output = open(log, "w") if log else subprocess.DEVNULL
        try:
            process = subprocess.Popen(self._wrap(host, argv), env=env, stdin=subprocess.DEVNULL,
                                       stdout=output, stderr=subprocess.STDOUT)
        finally:
            if log:
                output.close()
        self._processes.append(process)
        return process

    def run(self, host, argv, timeout=30, env=None):
        """Run ARGV on HOST to its end; a CompletedProcess with text stdout and stderr."""
        return subprocess.run(self._wrap(host, argv), env=env, stdin=subprocess.DEVNULL,
                              capture_output=True, text=True, timeout=timeout)

    def stop(self, process, timeout=5):
        """SIGTERM, then SIGKILL after TIMEOUT seconds; the exit status."""
        if process.poll() is None:
            process.send_signal(signal.SIGTERM)
            try:
                process.wait(timeout)
            except subprocess.TimeoutExpired:
                process.kill()
                process.wait()
        return process.returncode

    def _teardown(self):
        for process in self._processes:
            self.stop(process)
        self._processes.clear()
        for host in TOPOLOGIES[self.topology]:
            _sh("umount", f"/run/netlab/{host}/shm", check=False)
            _sh("ip", "netns", "del", host, check=False)
        _sh("ip", "link", "del", "br0", check=False)
