"""MAVLink 2 message signing: the key file format and the acceptance policy of a signed link.

A key file holds either 64 hexadecimal digits (the 32-byte secret itself) or a passphrase, whose
SHA-256 digest is the secret (the convention of MAVProxy's ``signing setup PASSPHRASE``).
Signing timestamps count 10 microseconds since 2015-01-01 00:00 UTC, as the MAVLink spec says.
"""

from __future__ import annotations

import hashlib
from pathlib import Path

SIGNING_EPOCH_UNIX_S = 1420070400.0
"""2015-01-01T00:00:00Z, the origin of MAVLink signing timestamps."""

UNSIGNED_ALLOWED_MSG_IDS: frozenset[int] = frozenset({0, 109})
"""Messages accepted unsigned on a signed link (HEARTBEAT, RADIO_STATUS), as PX4 does."""


class SigningKeyError(ValueError):
    """A key file that cannot be used; the message names the file and the problem."""


def key_from_text(text: str) -> bytes:
    """The 32-byte secret for a key file's text (hex secret or passphrase)."""
    stripped = text.strip()
    if not stripped:
        raise SigningKeyError("empty signing key")
    if len(stripped) == 64:
        try:
            return bytes.fromhex(stripped)
        except ValueError:
            pass
    return hashlib.sha256(stripped.encode("utf-8")).digest()


def load_signing_key(path: str | Path) -> bytes:
    """Read a key file; raises SigningKeyError naming the file when it is missing or empty."""
    file = Path(path)
    try:
        text = file.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        reason = "not UTF-8 text" if isinstance(exc, UnicodeDecodeError) else exc.strerror
        raise SigningKeyError(
            f"cannot read signing key file {file} ({reason or exc}); pass a text file holding "
            "the key: 64 hex digits or a passphrase"
        ) from None
    try:
        return key_from_text(text)
    except SigningKeyError as exc:
        raise SigningKeyError(f"{exc} in {file}") from None


def signing_timestamp(unix_time_s: float) -> int:
    """MAVLink signing timestamp (units of 10 us since 2015-01-01) for a Unix time [s]."""
    return max(0, int((unix_time_s - SIGNING_EPOCH_UNIX_S) * 100_000))
