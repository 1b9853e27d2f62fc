"""Security: anonymous only on loopback; users and client certificates over Basic256Sha256."""

import asyncio
import hashlib

import pytest
from asyncua import Client, ua
from asyncua.crypto.cert_gen import setup_self_signed_certificate
from asyncua.ua import uaerrors
from opcua_helpers import THESIS, Running, run_async
from cryptography.x509.oid import ExtendedKeyUsageOID

from stvm.opcua.config import load_config
from stvm.opcua.server import security_plan


def make_certificate(folder, name, uri, use):
    key, cert = folder / f"{name}_key.pem", folder / f"{name}_cert.der"
    asyncio.run(setup_self_signed_certificate(key, cert, uri, "localhost", [use], {"commonName": name}))
    return key, cert


@pytest.fixture(scope="module")
def pki(tmp_path_factory):
    folder = tmp_path_factory.mktemp("pki")
    server = make_certificate(folder, "server", "urn:stvm:CBT_Commands_Lib:server", ExtendedKeyUsageOID.SERVER_AUTH)
    scada = make_certificate(folder, "scada", "urn:example:scada", ExtendedKeyUsageOID.CLIENT_AUTH)
    stranger = make_certificate(folder, "stranger", "urn:example:stranger", ExtendedKeyUsageOID.CLIENT_AUTH)
    return folder, server, scada, stranger


def test_non_loopback_endpoint_offers_no_anonymous_and_no_plain_channel(pki):
    folder, (key, cert), (_, scada_cert), _ = pki
    table = {"certificate": str(cert), "private_key": str(key), "trusted_clients": [str(scada_cert)],
             "users": {"operator": "sha256:" + hashlib.sha256(b"pw").hexdigest()}}
    remote = load_config({"opcua": table}, None, THESIS, "opc.tcp://192.168.10.5:4840")
    policies, tokens = security_plan(remote)
    assert ua.SecurityPolicyType.NoSecurity not in policies
    assert ua.SecurityPolicyType.Basic256Sha256_SignAndEncrypt in policies
    assert ua.AnonymousIdentityToken not in tokens
    assert set(tokens) == {ua.UserNameIdentityToken, ua.X509IdentityToken}
    local = load_config({"opcua": {}}, None, THESIS, "opc.tcp://127.0.0.1:4840")
    assert security_plan(local) == ([ua.SecurityPolicyType.NoSecurity], [ua.AnonymousIdentityToken])


def test_users_and_certificates_over_basic256sha256(thesis_project, pki):
    folder, (key, cert), (scada_key, scada_cert), (stranger_key, stranger_cert) = pki
    table = {"certificate": str(cert), "private_key": str(key), "trusted_clients": [str(scada_cert)],
             "users": {"operator": "sha256:" + hashlib.sha256(b"s3cret").hexdigest()}}
    run = Running(thesis_project, table)
    secure = f"Basic256Sha256,SignAndEncrypt,{scada_cert},{scada_key}"

    async def client(user=None, password=None, identity=None, security=secure):
        c = Client(run.url, timeout=20)
        if security:
            await c.set_security_string(security)
        if user:
            c.set_user(user)
            c.set_password(password)
        if identity:
            await c.load_client_certificate(str(identity[1]))
            await c.load_private_key(str(identity[0]))
        return c

    async def body():
        operator = await client("operator", "s3cret")
        async with operator:
            ns = await operator.get_namespace_index(run.ns_uri)
            port = operator.get_node(ua.NodeId("Connect_Dest_PortIP", ns))
            await port.write_value(ua.Variant(1234, ua.VariantType.Int16))
            assert await port.read_value() == 1234
        with pytest.raises(uaerrors.BadUserAccessDenied):
            async with await client("operator", "wrong"):
                pass
        async with await client(identity=(scada_key, scada_cert)) as scada:   # certificate identity
            ns = await scada.get_namespace_index(run.ns_uri)
            assert await scada.get_node(ua.NodeId("Connect_Dest_PortIP", ns)).read_value() == 1234
        stranger = f"Basic256Sha256,SignAndEncrypt,{stranger_cert},{stranger_key}"
        with pytest.raises(uaerrors.BadUserAccessDenied):
            async with await client(identity=(stranger_key, stranger_cert), security=stranger):
                pass
        async with Client(run.url) as anonymous:        # loopback: anonymous over None is served
            assert await anonymous.get_namespace_index(run.ns_uri) >= 1
    try:
        run_async(body())
    finally:
        run.close()
