"""Body encryption: AES-256-CTR, key SHA-256(passphrase), IV SHA-256(header)[:16].

The AES key schedule is set up once per passphrase: an ECB encryptor of the key makes the CTR
keystream (the encrypted counter blocks IV, IV+1, ...) for every message, instead of a new CTR
cipher object per message.
"""

from __future__ import annotations

import hashlib

from cryptography.hazmat.primitives.ciphers import Cipher, algorithms, modes

_BLOCK = 16
_COUNTER_MASK = (1 << 128) - 1


class BodyCipher:
    def __init__(self, passphrase: str | bytes) -> None:
        secret = passphrase.encode() if isinstance(passphrase, str) else passphrase
        key = hashlib.sha256(secret).digest()
        # ECB over whole blocks keeps no state between calls: one encryptor serves all messages
        self._blocks = Cipher(algorithms.AES(key), modes.ECB()).encryptor()

    def apply(self, header: bytes, body: bytes) -> bytes:
        """Encrypts or decrypts (CTR mode is its own inverse) the body bytes."""
        n = len(body)
        if not n:
            return body
        counter = int.from_bytes(hashlib.sha256(header).digest()[:_BLOCK], "big")
        count = (n + _BLOCK - 1) // _BLOCK
        if count == 1:
            counters = counter.to_bytes(_BLOCK, "big")
        else:
            counters = b"".join(
                ((counter + i) & _COUNTER_MASK).to_bytes(_BLOCK, "big") for i in range(count)
            )
        stream = self._blocks.update(counters)
        mixed = int.from_bytes(body, "little") ^ int.from_bytes(stream[:n], "little")
        return mixed.to_bytes(n, "little")
