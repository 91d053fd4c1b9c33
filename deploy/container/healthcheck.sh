#!/bin/bash
# Container health check (Dockerfile HEALTHCHECK). A long-running `csgtile worker` is healthy
# when its health endpoint answers /healthz with 200 on 127.0.0.1:${CSGTILE_HEALTH_PORT:-9464};
# one-shot commands (run, enqueue, status) are healthy while they run.
# Uses bash's /dev/tcp, so the image needs no HTTP client.
set -u
cmdline="$(tr '\0' ' ' </proc/1/cmdline 2>/dev/null)"
case " $cmdline " in
  *" worker "*) ;;
  *) exit 0 ;;
esac
port="${CSGTILE_HEALTH_PORT:-9464}"
exec 3<>"/dev/tcp/127.0.0.1/$port" || exit 1
printf 'GET /healthz HTTP/1.0\r\nHost: localhost\r\n\r\n' >&3
read -r -t 4 status_line <&3 || exit 1
case "$status_line" in
  "HTTP/1."?" 200"*) exit 0 ;;
  *) exit 1 ;;
esac
