#!/usr/bin/env bash
# A pathfarm farm over several "hosts" on one Linux machine, without containers: each host is a network
# namespace with one veth cable to a bridge (in a namespace of its own), on a private /24. The machine
# itself is plugged into the same bridge, so the dashboard and the CLI work from an ordinary shell.
#
#   10.87.0.1    master       pathfarm-master --listen 10.87.0.1:7700 --http 10.87.0.1:8080
#   10.87.0.2..  worker1..N   pathfarm-worker --master 10.87.0.1:7700
#   10.87.0.254  this machine (interface <prefix>-host)
#
# Usage (as root: namespaces need CAP_NET_ADMIN):
#   farm-netns.sh up [--workers N] [--threads T] [--bin DIR]   build the topology, start master and workers
#   farm-netns.sh status                                       hosts, addresses, processes
#   farm-netns.sh cut HOST | heal HOST                         pull / plug back a host's cable (eth0 down/up)
#   farm-netns.sh exec HOST COMMAND...                         run a command on a host
#   farm-netns.sh down                                         stop everything and remove the namespaces
# Then, from this machine:
#   export PATHFARM_MASTER=10.87.0.1:7700 PATHFARM_TOKEN=$(cat /run/pathfarm-netns/client.token)
#   pathfarm submit scenes/cornell-box/scene.xml --spp 64 --wait -o out/cornell.exr
#   open http://10.87.0.1:8080/
#
# Environment: PF_NETNS_PREFIX (namespace prefix, default "pf"), PF_NETNS_SUBNET (first three octets,
# default 10.87.0), PF_NETNS_STATE (tokens, logs, pids; default /run/pathfarm-netns).
# tests/test_farm_netns.cpp builds the same topology (tests/farm/netns.cpp) for the test suite.
set -Eeuo pipefail

PREFIX=${PF_NETNS_PREFIX:-pf}
SUBNET=${PF_NETNS_SUBNET:-10.87.0}
STATE=${PF_NETNS_STATE:-/run/pathfarm-netns}
SWITCH=$PREFIX-switch
GRPC_PORT=7700
HTTP_PORT=8080

die() { echo "farm-netns: $*" >&2; exit 1; }
say() { echo "farm-netns: $*"; }

[ "$(id -u)" -eq 0 ] || die "run as root (network namespaces need CAP_NET_ADMIN)"
command -v ip >/dev/null || die "iproute2 ('ip') is not installed: apt-get install iproute2"

# Hosts of a running topology, in address order: master, worker1, worker2, ...
hosts() { ip netns list | awk '{print $1}' | grep -E "^$PREFIX-(master|worker[0-9]+)$" | sed "s/^$PREFIX-//" | sort -V; }

# Adds host $1 at address $SUBNET.$2: its namespace, loopback, and a cable to the switch.
add_host() {
  local name=$1 octet=$2 ns=$PREFIX-$1
  ip netns add "$ns"
  ip -n "$ns" link set lo up
  ip -n "$SWITCH" link add "p-$name" type veth peer name eth0 netns "$ns"
  ip -n "$SWITCH" link set "p-$name" master br0 up
  ip -n "$ns" addr add "$SUBNET.$octet/24" dev eth0
  ip -n "$ns" link set eth0 up
}

# Starts $2... on host $1 in the background, logging to $STATE/$1.log and recording its pid.
start_on() {
  local host=$1
  shift
  ip netns exec "$PREFIX-$host" setsid "$@" >"$STATE/$host.log" 2>&1 </dev/null &
  echo $! >"$STATE/$host.pid"
}

token() { head -c 16 /dev/urandom | od -An -tx1 | tr -d ' \n'; }

cmd_up() {
  local workers=2 threads=1 bin=""
  while [ $# -gt 0 ]; do
    case $1 in
      --workers) workers=$2; shift 2 ;;
      --threads) threads=$2; shift 2 ;;
      --bin) bin=$2; shift 2 ;;
      *) die "up: unknown option '$1'" ;;
    esac
  done
  [[ $workers =~ ^[0-9]+$ && $workers -ge 1 && $workers -le 250 ]] || die "up: --workers wants 1..250, got '$workers'"
  [[ $threads =~ ^[0-9]+$ && $threads -ge 1 ]] || die "up: --threads wants a positive number, got '$threads'"
  local master worker
  if [ -n "$bin" ]; then
    master=$bin/pathfarm-master worker=$bin/pathfarm-worker
  else
    master=$(command -v pathfarm-master || true) worker=$(command -v pathfarm-worker || true)
    [ -n "$master" ] || master=$(dirname "$0")/../../build/pathfarm-master
    [ -n "$worker" ] || worker=$(dirname "$0")/../../build/pathfarm-worker
  fi
  [ -x "$master" ] || die "no pathfarm-master at '$master' (build it, or pass --bin DIR)"
  [ -x "$worker" ] || die "no pathfarm-worker at '$worker' (build it, or pass --bin DIR)"
  master=$(realpath "$master") worker=$(realpath "$worker")
  ip netns list | grep -q "^$SWITCH\b" && die "a topology named '$PREFIX' is up already ('$0 down' first)"

  trap 'echo "farm-netns: up failed; cleaning up" >&2; cmd_down >/dev/null 2>&1' ERR
  mkdir -p "$STATE/data"
  [ -s "$STATE/client.token" ] || token >"$STATE/client.token"
  [ -s "$STATE/worker.token" ] || token >"$STATE/worker.token"
  chmod 600 "$STATE"/*.token

  ip netns add "$SWITCH"
  ip -n "$SWITCH" link add br0 type bridge
  ip -n "$SWITCH" link set br0 up
  # This machine's own cable, so that the farm is reachable without entering a namespace.
  ip link add "$PREFIX-host" type veth peer name p-host netns "$SWITCH"
  ip -n "$SWITCH" link set p-host master br0 up
  ip addr add "$SUBNET.254/24" dev "$PREFIX-host"
  ip link set "$PREFIX-host" up

  add_host master 1
  start_on master "$master" --listen "$SUBNET.1:$GRPC_PORT" --http "$SUBNET.1:$HTTP_PORT" --data "$STATE/data" \
    --token-file "$STATE/client.token" --worker-token-file "$STATE/worker.token"
  for i in $(seq 1 "$workers"); do
    add_host "worker$i" $((i + 1))
    start_on "worker$i" "$worker" --master "$SUBNET.1:$GRPC_PORT" --token-file "$STATE/worker.token" \
      --threads "$threads" --cache "$STATE/cache-worker$i" --name "worker$i"
  done
  trap - ERR
  say "master on $SUBNET.1:$GRPC_PORT, dashboard http://$SUBNET.1:$HTTP_PORT/, $workers workers; state in $STATE"
  say "export PATHFARM_MASTER=$SUBNET.1:$GRPC_PORT PATHFARM_TOKEN=\$(cat $STATE/client.token)"
}

cmd_down() {
  local h pid
  for h in $(hosts); do
    if [ -f "$STATE/$h.pid" ]; then
      pid=$(cat "$STATE/$h.pid")
      kill "$pid" 2>/dev/null || true
      rm -f "$STATE/$h.pid"
    fi
  done
  # Give master and workers their graceful shutdown, then remove the hosts (which takes their cables).
  sleep 1
  for h in $(hosts); do ip netns delete "$PREFIX-$h"; done
  ip link delete "$PREFIX-host" 2>/dev/null || true
  ip netns delete "$SWITCH" 2>/dev/null || true
  say "down (logs and data stay in $STATE)"
}

cmd_status() {
  ip netns list | grep -q "^$SWITCH\b" || { say "no topology named '$PREFIX' is up"; return 0; }
  local h addr link pid state
  printf '%-10s %-14s %-6s %-8s %s\n' HOST ADDRESS LINK PID PROCESS
  for h in $(hosts); do
    addr=$(ip -n "$PREFIX-$h" -4 -o addr show dev eth0 | awk '{print $4}')
    link=$(ip -n "$PREFIX-$h" -o link show dev eth0 | grep -q 'state UP' && echo up || echo down)
    pid=$(cat "$STATE/$h.pid" 2>/dev/null || echo -)
    state=$([ "$pid" != - ] && kill -0 "$pid" 2>/dev/null && echo running || echo stopped)
    printf '%-10s %-14s %-6s %-8s %s\n' "$h" "$addr" "$link" "$pid" "$state"
  done
}

host_ns() {
  [ $# -ge 1 ] || die "name a host: $(hosts | tr '\n' ' ')"
  ip netns list | grep -q "^$PREFIX-$1\b" || die "no host '$1' (hosts: $(hosts | tr '\n' ' '))"
  echo "$PREFIX-$1"
}

case ${1:-} in
  up) shift; cmd_up "$@" ;;
  down) cmd_down ;;
  status) cmd_status ;;
  cut) ns=$(host_ns "${2:-}"); ip -n "$ns" link set eth0 down; say "$2's cable pulled" ;;
  heal) ns=$(host_ns "${2:-}"); ip -n "$ns" link set eth0 up; say "$2's cable plugged back" ;;
  exec) ns=$(host_ns "${2:-}"); shift 2; exec ip netns exec "$ns" "$@" ;;
  *) sed -n '2,/^set -Eeuo/p' "$0" | sed '$d; s/^# \{0,1\}//'; exit 2 ;;
esac
