"""Body encryption (spec §20): AES-256-CTR, key SHA-256(passphrase), IV SHA-256(header)[:16]."""

from __future__ import annotations

import hashlib

from cryptography.hazmat.primitives.ciphers import Cipher, algorithms, modes


class BodyCipher:
    def __init__(self, passphrase: str | bytes) -> None:
        secret = passphrase.encode() if isinstance(passphrase, str) else passphrase
        self._key = hashlib.sha256(secret).digest()

    def apply(self, header: bytes, body: bytes) -> bytes:
        """Encrypts or decrypts (CTR mode is its own inverse) the body bytes."""
        if not body:
            return body
        iv = hashlib.sha256(header).digest()[:16]
        ctx = Cipher(algorithms.AES(self._key), modes.CTR(iv)).encryptor()
        return ctx.update(body) + ctx.finalize()
