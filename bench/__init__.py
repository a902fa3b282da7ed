"""omsd benchmarks (issues 7 and 16): measured speed and bounded cost, each figure beside its
baseline and its target.

``python -m bench`` runs them all (three to four minutes) and prints one table; ``python -m
bench --quick`` is the short version CI runs (about half a minute, few samples: it shows that
every row can be measured, the figures themselves mean little); ``--fast`` adds uvloop,
``--peers`` other simulators (:mod:`bench.envs` installs what they need into a cache).

Every figure is taken side by side with a baseline in the same run on the same machine, the
client pinned to one core and the servers to the others (:func:`bench.procs.pin`). The
baselines are the plainest servers that can answer on the same transport and the same loop
(:mod:`bench.echo`) and, below them, blocking I/O with no loop at all (:mod:`bench.floor`).
The benchmarks:

* :mod:`bench.latency`    ``RP`` round trip over TCP and the pty: omsd as users run it, view off,
  driver link, against the echoes and the floor (and on uvloop);
* :mod:`bench.versions`   the same under Python 3.12 and 3.13;
* :mod:`bench.interp`     one interpreter step in process; long motion on the manual clock;
* :mod:`bench.throughput` pipelined ``RP`` on one board; 100,000 mixed pipelined commands;
* :mod:`bench.cost`       CPU of idle boards and of boards in motion being polled, 1 to 128;
* :mod:`bench.watch`      ``omsd top`` open on 8 moving boards: the daemon's CPU rise, both
  sides' memory; a subscriber that never reads;
* :mod:`bench.scale`      1,000 boards in one daemon: ready time, memory, idle CPU;
* :mod:`bench.fidelity`   when a move's done marker arrives against the manual's profile;
* :mod:`bench.startup`    the commands a user types, and the daemon's first accept;
* :mod:`bench.isolation`  one board's replies while another's client misbehaves; churn cycles;
* :mod:`bench.peers`      other simulators beside omsd (``--peers`` only).

Beside the table, :mod:`bench.instructions` counts the machine instructions of one poll of the
load's board in the engine (valgrind): a figure that does not move with the machine's load;
:mod:`bench.opcodes` the bytecodes of one poll in the daemon's loop, by file and function.
"""
