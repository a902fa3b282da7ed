"""Record a real card's traffic and replay it through the emulator (issue 17).

``omsd record`` (:mod:`omsd.recording.record`) stands between a host application and a real
board (or another omsd), passes every byte both ways unchanged and writes both directions to a
JSON-lines file: a header naming the board (:mod:`omsd.recording.format`), then the traffic
records of the daemon's own traffic log (:mod:`omsd.telemetry.traffic`) with monotonic times.

``omsd replay`` (:mod:`omsd.recording.replay`) feeds the recorded host bytes to an emulated board
at their recorded times, in simulated time (:mod:`omsd.recording.emulate`), splits what the card
said and what omsd says into replies and markers (:mod:`omsd.recording.units`) and compares them
(:mod:`omsd.recording.compare`). It reads the daemon's own ``--log`` files too, so any session
served by omsd is a regression case. :mod:`omsd.recording.cli` has the two commands' options.

This package is imported by ``omsd``'s command line only when one of the two commands runs
(``omsd --help`` builds their parsers from :mod:`omsd.recording.cli`, which imports nothing
heavy at its top), and by :func:`omsd.testing.assert_replays`.
"""
