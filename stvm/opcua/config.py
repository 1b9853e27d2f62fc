"""The OPC UA server's settings: the `--opcua` endpoint and the manifest's `[opcua]` table.

```toml
[opcua]
endpoint = "opc.tcp://127.0.0.1:4840"     # what `--opcua` without a URL serves
publish = ["@globals", "@programs"]       # the default: globals and program variables, no FB internals
exclude = []                              # path patterns left out (with everything below them)
writable = ["@globals", "@program_inputs"]  # the default: globals and programs' VAR_INPUT
read_only = []                            # path patterns never writable (wins over `writable`)
start = "running"                         # or "paused": a virtual-clock run waits for Runtime.Scan/Resume
users = { operator = "env:STVM_OPCUA_PASSWORD" }   # or "sha256:<hex digest of the password>"
certificate = "pki/server_cert.der"       # server certificate and key: Basic256Sha256 endpoints
private_key = "pki/server_key.pem"
trusted_clients = ["pki/scada.der"]       # client certificates accepted as user identity

[opcua.limits]                            # any of the server's bounds (docs/opcua.md lists them all)
max_connections = 20
max_monitored_items_per_session = 2000
```

Entries of `publish`, `exclude`, `writable` and `read_only` are path patterns (the trace's glob
syntax: `Cobot.*`, `PnP_MoveParameters[*].Speed`, `PnP_Example_Instance.**`; a pattern naming a
struct, array or FB instance covers everything below it) or one of the sets `@globals`,
`@programs` (every variable of every program instance), `@program_inputs` (their VAR_INPUT) and
`@fb_internals` (members of FB instances). `@`-names cannot clash with ST names.

Security (checked here, before anything starts): an endpoint on a loopback address accepts
anonymous clients over SecurityPolicy None; any other address serves only Basic256Sha256
(Sign, SignAndEncrypt) with the configured certificate, and only to authenticated clients
(`users` or `trusted_clients`), never anonymous ones.
"""

from __future__ import annotations

import hashlib
import ipaddress
import math
import os
import re
from dataclasses import dataclass, field, fields
from pathlib import Path
from urllib.parse import urlsplit

DEFAULT_ENDPOINT = "opc.tcp://127.0.0.1:4840"
SETS = ("@globals", "@programs", "@program_inputs", "@fb_internals")
DEFAULT_PUBLISH = ("@globals", "@programs")
DEFAULT_WRITABLE = ("@globals", "@program_inputs")
KEYS = ("endpoint", "publish", "exclude", "writable", "read_only", "start", "users", "certificate",
        "private_key", "trusted_clients", "limits", "alarms")


@dataclass(frozen=True)
class ServerLimits:
    """Every bound of the server; the manifest's `[opcua.limits]` sets any of them."""
    max_chunk_size: int = 65535            # bytes of one chunk (the receive buffer offered in Acknowledge)
    max_message_size: int = 4 * 1024 * 1024  # bytes of one request or response, all its chunks
    max_connections: int = 100             # TCP connections, logged in or not
    max_sessions: int = 64
    max_pending_requests: int = 64         # requests queued per connection before it is closed
    login_timeout: float = 10.0            # seconds a connection may stay without an activated session
    max_session_timeout: float = 60.0      # seconds a session lives without its client (revised down to it)
    max_subscriptions_per_session: int = 10
    max_monitored_items_per_session: int = 2000
    max_queue_size: int = 100              # notifications a monitored item queues between two publishes
    min_publishing_interval: float = 10.0  # ms; faster requests are revised up to it
    max_interval: float = 3_600_000.0      # ms; slower publishing or sampling intervals are revised down to it

    @property
    def max_chunk_count(self) -> int:
        return math.ceil(self.max_message_size / self.max_chunk_size)


LIMIT_KEYS = tuple(f.name for f in fields(ServerLimits))
_FLOATS = {"login_timeout", "max_session_timeout", "min_publishing_interval", "max_interval"}
_MINIMUM = {"max_chunk_size": 8192, "max_message_size": 8192}   # OPC UA Part 6: buffers of at least 8192 bytes


def limits_from(table, where: str) -> ServerLimits:
    """`[opcua.limits]` read into ServerLimits; raises OpcUaConfigError naming the bad key."""
    if table is None:
        return ServerLimits()
    if not isinstance(table, dict):
        raise OpcUaConfigError(f"{where}: must be a table")
    unknown = sorted(set(table) - set(LIMIT_KEYS))
    if unknown:
        raise OpcUaConfigError(f"{where}: unknown key(s) {', '.join(unknown)} (known: {', '.join(LIMIT_KEYS)})")
    values = {}
    for key, value in table.items():
        kind = "a number" if key in _FLOATS else "an integer"
        ok = isinstance(value, (int, float)) and not isinstance(value, bool) if key in _FLOATS else \
            isinstance(value, int) and not isinstance(value, bool)
        if not ok or not math.isfinite(value) or value <= 0 or value < _MINIMUM.get(key, 0) or value > 2**31:
            low = _MINIMUM.get(key)
            raise OpcUaConfigError(f"{where} {key}: expected {kind} greater than 0"
                                 f"{f' and at least {low}' if low else ''} (up to 2^31), got {value!r}")
        values[key] = float(value) if key in _FLOATS else value
    limits = ServerLimits(**values)
    if limits.max_message_size < limits.max_chunk_size:
        raise OpcUaConfigError(f"{where}: max_message_size ({limits.max_message_size}) is smaller than "
                                 f"max_chunk_size ({limits.max_chunk_size})")
    if limits.min_publishing_interval > limits.max_interval:
        raise OpcUaConfigError(f"{where}: min_publishing_interval is above max_interval")
    return limits


def revise_interval(requested, fastest: float, slowest: float) -> float | None:
    """A requested publishing or sampling interval (ms) revised into [fastest, slowest] (OPC UA
    Part 4: 0 and negative ask for the fastest); None for NaN, which asks for nothing."""
    if not isinstance(requested, (int, float)) or math.isnan(requested):
        return None
    if requested <= fastest:
        return fastest
    return min(float(requested), slowest)


class OpcUaConfigError(ValueError):
    """A bad `--opcua` URL or `[opcua]` entry (the message names it; `stvm` exits 2)."""


@dataclass(frozen=True)
class Endpoint:
    url: str
    host: str
    port: int          # 0: an ephemeral port, chosen when the server starts (tests)
    path: str = ""

    @property
    def loopback(self) -> bool:
        return is_loopback(self.host)


@dataclass(frozen=True)
class OpcUaConfig:
    endpoint: Endpoint
    project_name: str
    publish: tuple[str, ...] = DEFAULT_PUBLISH
    exclude: tuple[str, ...] = ()
    writable: tuple[str, ...] = DEFAULT_WRITABLE
    read_only: tuple[str, ...] = ()
    start_paused: bool = False
    alarms: bool = True          # Alarms & Conditions events of the FB errors (stvm/opcua/alarms.py)
    users: dict[str, str] = field(default_factory=dict)   # user name → sha256 hex of the password
    certificate: Path | None = None
    private_key: Path | None = None
    trusted_clients: tuple[Path, ...] = ()
    limits: ServerLimits = field(default_factory=lambda: ServerLimits())
    # the project's manifest and folder: the operator limits table (stvm/frontend/limits.py) is read from them
    manifest: dict = field(default_factory=dict, compare=False, repr=False)
    root: Path | None = None

    @property
    def namespace_uri(self) -> str:
        return f"urn:stvm:{self.project_name}"

    @property
    def secure(self) -> bool:
        """Basic256Sha256 endpoints are served (a certificate is configured)."""
        return self.certificate is not None


def is_loopback(host: str) -> bool:
    if host.lower() == "localhost":
        return True
    try:
        return ipaddress.ip_address(host).is_loopback
    except ValueError:
        return False


def parse_endpoint(text: str, where: str = "--opcua") -> Endpoint:
    """`opc.tcp://HOST:PORT[/PATH]`, or `HOST:PORT` for short (as `--hmi` takes its address);
    raises OpcUaConfigError with an example."""
    example = f"{where}: expected opc.tcp://HOST:PORT (for example {DEFAULT_ENDPOINT}), got {text!r}"
    if "://" not in text and re.fullmatch(r"\s*(\[[0-9A-Fa-f:.]+\]|[^\s:/\[\]]+):\d+\s*", text):
        text = "opc.tcp://" + text.strip()
    try:
        parts = urlsplit(text.strip())
        port = parts.port
    except ValueError:
        raise OpcUaConfigError(example) from None
    if parts.scheme != "opc.tcp" or not parts.hostname or port is None or parts.query or parts.fragment:
        raise OpcUaConfigError(example)
    if parts.username or parts.password:
        raise OpcUaConfigError(f"{where}: put users in the manifest's [opcua] users, not in the URL")
    host = parts.hostname
    if not _valid_host(host):
        raise OpcUaConfigError(example)
    return Endpoint(text.strip(), host, port, parts.path.rstrip("/"))


def _valid_host(host: str) -> bool:
    try:
        ipaddress.ip_address(host)
        return True
    except ValueError:
        return re.fullmatch(r"[A-Za-z0-9]([A-Za-z0-9-]*[A-Za-z0-9])?(\.[A-Za-z0-9]([A-Za-z0-9-]*[A-Za-z0-9])?)*",
                            host) is not None


def project_name(manifest: dict, root: Path | None, files) -> str:
    """`[project] name`, else the manifest folder's name, else the first file's stem."""
    name = manifest.get("project", {}).get("name") if isinstance(manifest.get("project"), dict) else None
    if not name:
        name = root.resolve().name if root is not None else (Path(files[0]).stem if files else "project")
    return re.sub(r"[^A-Za-z0-9_.-]", "_", str(name))


def load_config(manifest: dict, root: Path | None, files, endpoint_arg: str | None) -> OpcUaConfig:
    """The settings of one run: `endpoint_arg` (the `--opcua` value, None for the default) over
    the manifest's `[opcua]` table. Paths are relative to the manifest's folder."""
    table = manifest.get("opcua", {})
    where = "stvm.toml [opcua]"
    if not isinstance(table, dict):
        raise OpcUaConfigError(f"{where}: must be a table")
    unknown = sorted(set(table) - set(KEYS))
    if unknown:
        raise OpcUaConfigError(f"{where}: unknown key(s) {', '.join(unknown)} (known: {', '.join(KEYS)})")
    base = root or Path(".")
    if endpoint_arg:
        endpoint = parse_endpoint(endpoint_arg)
    else:
        endpoint = parse_endpoint(_string(table, "endpoint", DEFAULT_ENDPOINT, where), f"{where} endpoint")
    start = _string(table, "start", "running", where)
    if start not in ("running", "paused"):
        raise OpcUaConfigError(f"{where} start: expected \"running\" or \"paused\", got {start!r}")
    config = OpcUaConfig(
        endpoint=endpoint,
        project_name=project_name(manifest, root, files),
        publish=_rules(table, "publish", DEFAULT_PUBLISH, where),
        exclude=_rules(table, "exclude", (), where),
        writable=_rules(table, "writable", DEFAULT_WRITABLE, where),
        read_only=_rules(table, "read_only", (), where),
        start_paused=start == "paused",
        alarms=_bool(table, "alarms", True, where),
        users=_users(table.get("users", {}), where),
        certificate=_path(table, "certificate", base, where),
        private_key=_path(table, "private_key", base, where),
        trusted_clients=tuple(_file(base, p, f"{where} trusted_clients") for p in
                              _string_list(table, "trusted_clients", (), where)),
        limits=limits_from(table.get("limits"), f"{where} limits"),
        manifest=manifest,
        root=root,
    )
    _check_security(config, where)
    return config


def _check_security(config: OpcUaConfig, where: str) -> None:
    if (config.certificate is None) != (config.private_key is None):
        raise OpcUaConfigError(f"{where}: certificate and private_key go together (Basic256Sha256 needs both)")
    if config.endpoint.loopback:
        return
    how = ("set [opcua] certificate and private_key (the server's Basic256Sha256 certificate, e.g. made with "
           "`openssl req -x509 -newkey rsa:2048 -nodes -keyout server_key.pem -outform DER -out server_cert.der "
           "-days 365 -subj /CN=stvm -addext subjectAltName=URI:urn:stvm:server`) and users or trusted_clients")
    if not config.secure:
        raise OpcUaConfigError(f"{config.endpoint.url} is not a loopback address: anonymous and unencrypted "
                               f"access is only served on loopback; {how}")
    if not config.users and not config.trusted_clients:
        raise OpcUaConfigError(f"{config.endpoint.url} is not a loopback address: clients must authenticate; "
                               f"add [opcua] users or trusted_clients")


def _string(table: dict, key: str, default: str, where: str) -> str:
    value = table.get(key, default)
    if not isinstance(value, str) or not value.strip():
        raise OpcUaConfigError(f"{where} {key}: expected a string, got {value!r}")
    return value


def _bool(table: dict, key: str, default: bool, where: str) -> bool:
    value = table.get(key, default)
    if not isinstance(value, bool):
        raise OpcUaConfigError(f"{where} {key}: expected true or false, got {value!r}")
    return value


def _string_list(table: dict, key: str, default: tuple, where: str) -> tuple[str, ...]:
    value = table.get(key, list(default))
    if isinstance(value, str) or not isinstance(value, list) or \
            not all(isinstance(v, str) and v.strip() for v in value):
        raise OpcUaConfigError(f"{where} {key}: expected a list of strings, got {value!r}")
    return tuple(v.strip() for v in value)


def _rules(table: dict, key: str, default: tuple, where: str) -> tuple[str, ...]:
    rules = _string_list(table, key, default, where)
    for rule in rules:
        if rule.startswith("@") and rule.lower() not in SETS:
            raise OpcUaConfigError(f"{where} {key}: unknown set {rule!r} (sets: {', '.join(SETS)})")
    return tuple(r.lower() if r.startswith("@") else r for r in rules)


def _path(table: dict, key: str, base: Path, where: str) -> Path | None:
    if key not in table:
        return None
    return _file(base, _string(table, key, "", where), f"{where} {key}")


def _file(base: Path, text: str, where: str) -> Path:
    path = (base / text) if not Path(text).is_absolute() else Path(text)
    if not path.is_file():
        raise OpcUaConfigError(f"{where}: no such file: {path}")
    return path


def _users(value, where: str) -> dict[str, str]:
    if not isinstance(value, dict):
        raise OpcUaConfigError(f"{where} users: expected a table of name = \"env:VAR\" or \"sha256:HEX\"")
    users = {}
    for name, secret in value.items():
        if not isinstance(secret, str):
            raise OpcUaConfigError(f"{where} users.{name}: expected \"env:VAR\" or \"sha256:HEX\", got {secret!r}")
        kind, _, rest = secret.partition(":")
        if kind == "env":
            password = os.environ.get(rest)
            if not rest or password is None:
                raise OpcUaConfigError(f"{where} users.{name}: environment variable {rest!r} is not set")
            users[name] = hashlib.sha256(password.encode("utf-8")).hexdigest()
        elif kind == "sha256" and re.fullmatch(r"[0-9a-fA-F]{64}", rest):
            users[name] = rest.lower()
        else:
            # Choice: no clear-text passwords in a manifest that is checked in with the sources
            raise OpcUaConfigError(f"{where} users.{name}: expected \"env:VAR\" (the password in an environment "
                                   f"variable) or \"sha256:HEX\" (its SHA-256 digest, 64 hex digits)")
    return users
