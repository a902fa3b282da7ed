"""The engine: the dialect-free core of an OMS motion control card (clock, axes and their
motion, queues, the executor, the servo loop, contouring, the simulated world, registers and
events). Pure: time is an argument of every call; nothing here sleeps, reads a clock or imports
asyncio, and nothing here knows a command language (``docs/architecture.md``).
"""
