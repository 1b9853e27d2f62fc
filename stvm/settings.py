"""Settings for every point the Sysmac spec marks UNCERTAIN (shared/spec/sysmac.md, section 9).

Each UNCERTAIN behaviour is exactly one named field here, with the spec's default. The VM, the
checker and the stdlib read them from the one `SysmacSettings` instance a run carries
(`ctx.settings`), so switching a behaviour is one line: `SysmacSettings(int_literal_type="lint")`,
or on the command line `stvm run --sysmac int_literal_type=lint ...`.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace


def _bsd_connection_states() -> dict[str, int]:
    # Choice (spec 5, `connection_state_values`): BSD order of the TCP states.
    names = ["_CLOSED", "_LISTEN", "_SYN_SENT", "_SYN_RECEIVED", "_ESTABLISHED", "_CLOSE_WAIT",
             "_FIN_WAIT1", "_CLOSING", "_LAST_ACK", "_FIN_WAIT2", "_TIME_WAIT"]
    return {name: value for value, name in enumerate(names)}


def _default_skt_error_codes() -> dict[str, int]:
    # Choice (spec 5, `skt_error_codes`): the mapping the spec proposes.
    return {
        "out_of_range": 0x0400,      # Size 0 / too large, DstTcpPort 0, bad TimeOut
        "too_few_elements": 0x0407,  # fewer array elements left than Size
        "port_in_use": 0x2001,
        "unresolvable": 0x2002,
        "wrong_state": 0x2003,       # refused, not connected, peer reset
        "timeout": 0x2006,           # 75 s connect, receive timeout
        "bad_handle": 0x2007,        # handle 0, unknown, or closed by SktClose
        "too_many_sockets": 0x2008,  # more than 16 sockets
    }


@dataclass(frozen=True)
class SysmacSettings:
    """One field per UNCERTAIN item of the Sysmac spec; defaults are the spec's."""

    # section 1: execution model
    skt_progress_without_call: str = "on"          # on | cancel
    enum_default: str = "first"                    # first | zero
    fun_error_policy: str = "skip_assignment"      # skip_assignment | fault
    array_oob: str = "fault"
    int_div_zero: str = "fault"                    # fault | zero
    # section 2: types
    int_literal_type: str = "dint"                 # dint | lint
    string_length_unit: str = "utf8"               # utf8 | bytes
    string_overflow: str = "truncate_warn"         # truncate_warn | error
    # section 3: dialect
    bare_enumerators: str = "resolve_unique"       # resolve_unique | require_type
    dollar_n: str = "lf"                           # lf | crlf
    invalid_dollar_escape: str = "error"           # error | literal
    double_quote_strings: str = "accept_warn"      # accept_warn | error
    for_end_eval: str = "once"                     # once | each
    # section 4/5: sockets
    skt_send_copy: str = "at_start"                # at_start | at_service
    skt_errorid_reset: str = "start_and_clear"     # start_and_clear | start_only
    skt_min_latency_calls: int = 1
    sockaddr_portno_type: str = "UINT"             # UINT | UDINT
    connection_state_values: dict = field(default_factory=_bsd_connection_states)
    byte_order_values: dict = field(default_factory=lambda: {"_LOW_HIGH": 0, "_HIGH_LOW": 1})
    skt_connect_srcport0: str = "ephemeral"        # ephemeral | error
    skt_socket_after_close: str = "unchanged"      # unchanged | zeroed
    skt_status_closed_handle: str = "done_closed"  # done_closed | error
    skt_send_size0: str = "done"                   # done | error
    skt_send_max: int = 2000
    skt_rcv_timeout0: str = "forever"              # forever | error_if_empty
    skt_rcv_timeout_unit_ns: int = 100_000_000
    skt_rcv_peer_closed: str = "done_zero"         # done_zero | error
    skt_error_codes: dict = field(default_factory=_default_skt_error_codes)
    # section 6: Omron functions
    toarybyte_string_model: str = "text_nul"       # text_nul | text | image
    toarybyte_wide_order: str = "big_endian"       # big_endian | word_swapped
    arytostring_oversize: str = "error"            # error | truncate
    rtfs_rounding: str = "half_away"               # half_away | half_even
    rtfs_negative_zero: str = "minus"              # minus | plus
    rtfs_max_minlen: int = 24                      # `rtfs_limits`
    rtfs_max_decplace: int = 7                     # `rtfs_limits`
    byte_to_string_format: str = "hex_nopad"       # hex_nopad | hex_pad2 | decimal
    stou_trailing: str = "error"                   # error | ignore_blanks
    stou_plus: str = "accept"                      # accept | error
    gettime_resolution_ns: int = 1_000_000
    sectodt_range: str = "error"                   # error | clamp
    # section 7: IEC library
    timer_clock: str = "scan_start"                # scan_start | call_time
    rtrig_first_call: str = "fire"                 # fire | no_fire
    ton_pt_below_et: str = "q_true"                # q_true | keep_timing
    ton_nonpositive_pt_et: str = "zero"            # zero | pt
    iec_pin_aliases: str = "on"                    # on | off
    string_result_overflow: str = "error"          # error | truncate
    string_fn_range: str = "error"                 # error | clamp
    concat_arity: str = "one_warns"                # one_warns | two_or_more
    find_empty: int = 0                            # 0 | 1

    def with_overrides(self, assignments: list[str]) -> "SysmacSettings":
        """Return a copy with `name=value` strings applied (from `--sysmac name=value`)."""
        known = {f.name: f for f in fields(self)}
        changes: dict[str, object] = {}
        for item in assignments:
            name, sep, text = item.partition("=")
            name = name.strip()
            if not sep or name not in known:
                raise ValueError(f"unknown Sysmac setting {item!r}; known: {', '.join(sorted(known))}")
            current = getattr(self, name)
            if isinstance(current, bool):
                changes[name] = text.strip().lower() in ("1", "true", "on", "yes")
            elif isinstance(current, int):
                changes[name] = int(text.strip().replace("_", ""), 0)
            elif isinstance(current, str):
                changes[name] = text.strip()
            else:
                raise ValueError(f"setting {name} is a table; set it from the Python API")
        return replace(self, **changes)


DEFAULT_SETTINGS = SysmacSettings()
