"""omsd benchmarks (issue 7): measured speed and bounded cost, each figure beside its baseline.

``python -m bench`` runs them all (a minute or two) and prints one table; ``python -m bench
--quick`` is the short version CI runs (a few seconds, few samples: it shows that every row can
be measured, the figures themselves mean little).

Every figure is taken side by side with a baseline in the same run on the same machine, because
the machine may be shared and busy: the baseline is a bare asyncio server (:mod:`bench.echo`)
doing the least a server can do on the same transport with the same bytes. The benchmarks:

* :mod:`bench.latency`   ``RP`` round trip over TCP and over the pty, median and p99;
* :mod:`bench.throughput` 100,000 pipelined commands (queries and queued moves) on one link;
* :mod:`bench.cost`      CPU of idle boards and of boards in motion being polled, 1/8/32 boards;
* :mod:`bench.fidelity`  when a move's done marker arrives against the manual's profile;
* :mod:`bench.startup`   from exec to the first endpoint accepting a connection.
"""
