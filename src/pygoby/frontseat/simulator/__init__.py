"""The basic (ABC) frontseat simulator: wire protocol, sans-I/O core, asyncio TCP server."""
