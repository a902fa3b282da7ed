# omsd in a container, for CI: emulated OMS boards on TCP, as a service next to the tests.
#
#   docker build -t omsd .
#   docker run --rm -p 7048:7048 omsd                      # a PC48-4E on localhost:7048
#   docker run --rm -p 7001-7003:7001-7003 omsd --config /etc/omsd/ci.toml
#   docker run --rm omsd models                            # anything after the image: omsd's args
#
# docs/deploy.md has a compose file and how to point a client at it.
#
# Why a config file and not `omsd --tcp 0.0.0.0:7048` by default: the health check must talk to
# a board (send WY, get the answer) without touching the board your tests use. A board has one
# TCP client at a time, and by default a newcomer takes the board over, closing the connection
# already there: a health check on the tests' board would cut them off at every interval. So
# the default configuration has two boards: "board1" on 0.0.0.0:7048 for clients, and "health"
# on the container's own loopback, 127.0.0.1:7049 (not exposed, unreachable from outside), for
# the check. A configuration of your own gets the check by including the same "health" board;
# otherwise run with --no-healthcheck.

FROM python:3.11-slim

# No .pyc writing at run time (pip compiles at install), log lines as they happen, a lean pip.
ENV PYTHONDONTWRITEBYTECODE=1 \
    PYTHONUNBUFFERED=1 \
    PIP_NO_CACHE_DIR=1 \
    PIP_DISABLE_PIP_VERSION_CHECK=1 \
    PIP_ROOT_USER_ACTION=ignore

# An unprivileged user with a fixed numeric id (Kubernetes' runAsNonRoot can check it) to run
# the daemon: it needs no privilege to serve TCP on ports above 1023.
RUN useradd --system --uid 10001 --user-group --no-create-home --home-dir /nonexistent \
      --shell /usr/sbin/nologin omsd

# The package: what pyproject.toml needs to build (itself, README.md, omsd/). .dockerignore keeps
# everything else (tests, .venv, .git) out of the build context.
COPY pyproject.toml README.md /tmp/omsd-src/
COPY omsd/ /tmp/omsd-src/omsd/
RUN pip install /tmp/omsd-src && rm -rf /tmp/omsd-src && omsd models > /dev/null

# The example configurations (ci.toml, ...) and the image's default, /etc/omsd/container.toml.
COPY config/ /etc/omsd/
RUN printf '%s\n' \
      '# The omsd image default (Dockerfile CMD).' \
      '# board1: a PC48-4E for clients, on every interface of the container: publish 7048.' \
      '# health: the HEALTHCHECK board, on the loopback only, so the check never takes board1' \
      '#         over from a connected client.' \
      '' \
      '[log]' \
      'view = "plain"' \
      '' \
      '[[board]]' \
      'name = "board1"' \
      'model = "PC48-4E"' \
      'tcp = "0.0.0.0:7048"' \
      '' \
      '[[board]]' \
      'name = "health"' \
      'model = "PC48-2"' \
      'tcp = "127.0.0.1:7049"' \
    > /etc/omsd/container.toml

# From here on, and for the daemon: the unprivileged user created above.
USER 10001:10001

EXPOSE 7048

# Healthy when the health board answers WY on the driver link: "PC48 ver ..." and the default
# end-of-string character, LF. Any failure (refused, timed out, wrong answer) exits non-zero.
HEALTHCHECK --interval=30s --timeout=5s --start-period=10s --retries=3 \
    CMD ["python", "-c", "import socket; s = socket.create_connection(('127.0.0.1', 7049), timeout=3); s.sendall(b'WY'); r = s.makefile('rb').readline(); raise SystemExit(0 if r.startswith(b'PC48 ver ') and r.endswith(b'\\n') else 1)"]

# The daemon stops cleanly on SIGTERM (docker stop), which it receives directly: the exec form
# makes omsd PID 1, with no shell in between.
STOPSIGNAL SIGTERM
ENTRYPOINT ["omsd"]
CMD ["--config", "/etc/omsd/container.toml"]
