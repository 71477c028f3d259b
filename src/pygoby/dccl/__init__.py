"""DCCL: the Dynamic Compact Control Language (byte-compatible with the C++ DCCL library)."""
