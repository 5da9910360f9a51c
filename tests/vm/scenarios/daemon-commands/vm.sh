# SPDX-License-Identifier: Apache-2.0
# Scenario 2, commands: cansend to the streaming tacse3d: valid commands ACKed, bad ones NACKed/ignored.
# shellcheck shell=sh
# vm-arch: aarch64
# vm-timeout: 90
set -eu
. /tacse3/lib.sh

vivid_two_sensors
vcan_up vcan0
need_daemon

daemon_streaming ./board.toml
sleep 1
# send SEQ FRAME: one command frame, then time for its Ack (the gripper answers within a cycle).
send() { log "seq $1: cansend vcan0 $2"; cansend vcan0 "$2" || fail "cansend $2"; sleep 0.3; }
send 1 "$(tacse3_cmd 030 1 01 00 00 00 00 1)"            # TARE -> ACK
send 2 "$(tacse3_cmd 030 1 02 00 00 00 00 2)"            # RESET_POSE -> ACK
send 3 "$(tacse3_cmd 030 1 03 A0 0F 00 00 3)"            # SET_FINGER_SEPARATION 0.04000 m -> ACK
send 4 "$(tacse3_cmd 030 1 07 02 00 00 00 4)"            # QUERY FINGER_SEPARATION -> ACK, 4000
send 5 "$(tacse3_cmd 030 1 0A 00 00 00 00 5)"            # unknown code 0x0A -> NACK UNKNOWN_COMMAND
good=$(tacse3_cmd 030 1 01 00 00 00 00 6)
send 6 "${good%??}$(printf '%02X' $(( (0x${good#"${good%??}"}) ^ 0x55 )))"   # TARE, CRC wrong -> BAD_CRC
send 7 "$(tacse3_cmd 030 1 01 00 00 00 00 7 | cut -c1-18)"   # TARE, 7 bytes -> NACK BAD_LENGTH
send 8 "$(tacse3_cmd 030 2 01 00 00 00 00 8)"            # node 1's id, TargetNode 2 -> NACK WRONG_NODE
send 9 "$(tacse3_cmd 030 1 03 32 00 00 00 9)"            # separation 0.0005 m < 0.001 -> OUT_OF_RANGE
send 10 "$(tacse3_cmd 030 1 01 00 00 00 00 10 1)"        # TARE, reserved bit 48 set -> RESERVED_NOT_ZERO
send 11 "$(tacse3_cmd 050 2 01 00 00 00 00 11)"          # TARE to node 2 -> ignored by node 1
sleep 0.7                      # one more periodic Status with RejectedCommands
kill -0 "$DAEMON_PID" || fail "tacse3d died during the commands"
daemon_stop_timed
candump_stop
expect_eq "$(kv "$TACSE3_OUT/stop.txt" exit)" 0 "tacse3d exit status after SIGTERM"
