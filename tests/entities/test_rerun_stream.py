"""The Rerun stream's ``serve`` sink: where it listens (read back from the kernel's socket table)."""

from __future__ import annotations

import socket
from pathlib import Path

import pytest

from dgraph.entities.recording import rerun_stream
from dgraph.entities.recording.rerun_stream import ServeAddress, open_stream, serving_on
from dgraph.errors import GraphError

LISTEN = "0A"
"""The state of a listening socket in /proc/net/tcp."""


def listening(port: int) -> set[str]:
    """The local addresses of the TCP sockets listening on ``port`` (IPv4 and IPv6), from
    /proc/net/tcp and /proc/net/tcp6: what ``ss -ltn`` shows, for every process."""
    found = set()
    for table, family in (("tcp", socket.AF_INET), ("tcp6", socket.AF_INET6)):
        for line in Path(f"/proc/net/{table}").read_text().splitlines()[1:]:
            local, state = line.split()[1], line.split()[3]
            address, hex_port = local.split(":")
            if state == LISTEN and int(hex_port, 16) == port:
                raw = bytes.fromhex(address)  # 32-bit words in host (little-endian) order
                found.add(socket.inet_ntop(family, b"".join(raw[i:i + 4][::-1] for i in range(0, len(raw), 4))))
    return found


def test_the_listing_reads_a_socket_back():
    with socket.socket() as server:
        server.bind(("127.0.0.1", 0))
        server.listen()
        assert listening(server.getsockname()[1]) == {"127.0.0.1"}


def test_serve_listens_on_loopback_by_default_and_prints_the_viewer_url(ports, monkeypatch, capsys):
    grpc, web = ports
    monkeypatch.setattr(rerun_stream, "SERVE", ServeAddress(grpc_port=grpc, web_port=web))  # the default bind
    stream = open_stream("serve-test", "serve", None, 0.001, owner=object())
    try:
        assert listening(grpc) == {"127.0.0.1"} and listening(web) == {"127.0.0.1"}
        assert stream.url == f"rerun+http://127.0.0.1:{grpc}/proxy"
        assert stream.viewer_url == f"http://127.0.0.1:{web}/?url=rerun%2Bhttp%3A%2F%2F127.0.0.1%3A{grpc}%2Fproxy"
        assert stream.viewer_url in capsys.readouterr().err
    finally:
        stream.close()
    assert listening(grpc) == set() and listening(web) == set()  # stopped with the stream


def test_serve_listens_where_it_is_told(ports):
    grpc, web = ports
    default = rerun_stream.SERVE
    with serving_on("127.0.0.2", grpc, web):  # another address of this machine, wider than the default
        stream = open_stream("serve-test", "serve", None, 0.001, owner=object())
        try:
            assert listening(grpc) == {"127.0.0.2"} and listening(web) == {"127.0.0.2"}
        finally:
            stream.close()
    assert rerun_stream.SERVE is default  # for the block only


def test_a_port_in_use_is_reported_before_starting(ports):
    grpc, web = ports
    with socket.socket() as squatter:
        squatter.bind(("127.0.0.1", grpc))
        squatter.listen()
        with pytest.raises(GraphError, match=f"cannot listen on 127.0.0.1:{grpc}"):
            rerun_stream.RerunServer(ServeAddress("127.0.0.1", grpc, web))
    assert listening(web) == set()


def test_a_wildcard_bind_is_reached_on_loopback_and_shown_by_host_name():
    assert ServeAddress("0.0.0.0").local_host() == "127.0.0.1" and ServeAddress("::").local_host() == "::1"
    assert ServeAddress("0.0.0.0").public_host() == socket.gethostname()
    with pytest.raises(GraphError, match="'localhost': not an IP address"), serving_on("localhost"):
        pass
