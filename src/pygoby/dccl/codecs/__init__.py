"""DCCL field codecs: one class per field kind and codec version, looked up by name in a registry."""
