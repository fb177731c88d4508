"""TLS and tokens, as dmpctl's flags: the default secured server is reached only with the cell's CA and an
identity (a bearer token, or a client certificate)."""

import subprocess

import grpc
import pytest

import dmp_cell
from server import server_binary


def test_a_token_over_tls_names_the_identity(server):
    with server.client("planner") as c:
        info = c.info()
    assert info.tls and info.mutual_tls and info.access_control and not info.insecure
    assert (info.identity, info.role) == ("planner", "planner")


def test_a_client_certificate_names_the_identity(server):
    s = server.set_dir
    with server.client(None, tls_cert=s / "observer.pem", tls_key=s / "observer.key") as c:
        info = c.info()
    assert (info.identity, info.role) == ("observer", "observer")


def test_the_server_name_can_be_given(server):
    # The server's certificate is for localhost, 127.0.0.1 and ::1: the name is checked, not just any name taken.
    with server.client("planner", server_name="localhost") as c:
        assert c.info().identity == "planner"
    with pytest.raises(dmp_cell.ConnectError):
        server.client("planner", server_name="elsewhere.example", timeout=1.0)


def test_without_an_identity_calls_are_unauthenticated(server):
    with server.client(None) as c:
        with pytest.raises(dmp_cell.StatusError) as e:
            c.list_primitives("r1")
    assert e.value.code == grpc.StatusCode.UNAUTHENTICATED
    with server.client(None, token="0" * 64) as c:
        with pytest.raises(dmp_cell.StatusError) as e:
            c.list_obstacles()
    assert e.value.code == grpc.StatusCode.UNAUTHENTICATED


def test_tls_needs_the_right_ca(server, tmp_path):
    # Plaintext against the TLS server, and TLS trusting another cell's CA, do not connect.
    with pytest.raises(dmp_cell.ConnectError):
        dmp_cell.Client(server.address, token_file=server.token("planner"), timeout=1.0)
    other = tmp_path / "other"
    subprocess.run([str(server_binary()), "access", "init", str(other), "--cell", "cell-b"], check=True,
                   capture_output=True, timeout=60)
    with pytest.raises(dmp_cell.ConnectError):
        server.client("planner", tls_ca=other / "ca.pem", timeout=1.0)


def test_bad_options_are_refused_before_connecting(server):
    with pytest.raises(dmp_cell.ArgumentError) as e:
        dmp_cell.Client("https://" + server.address)
    assert e.value.field == "tls_ca"
    with pytest.raises(dmp_cell.ArgumentError) as e:
        server.client(None, tls_cert=server.set_dir / "observer.pem")
    assert e.value.field == "tls_cert"
    with pytest.raises(dmp_cell.ArgumentError) as e:
        server.client(None, token="a token")
    assert e.value.field == "token"
