# Sourced by the system tests: exports ROS_DOMAIN_ID, a DDS domain no other test process on this
# machine holds. Same lock files and range as unav::testing::unique_domain_id() (gtest node
# tests): an exclusive flock on /tmp/unav_test_domain_<N>.lock, kept on fd 9 for the life of the
# test shell and inherited by the processes it launches, released by the kernel when they exit.
unav_pick_test_domain() {
  local start=$(($$ % 41)) i d
  for i in $(seq 0 40); do
    d=$((1 + (start + i) % 41))
    exec 9>>"/tmp/unav_test_domain_$d.lock" || continue
    if flock -n 9; then
      export ROS_DOMAIN_ID=$d
      return 0
    fi
    exec 9>&-
  done
  echo "test_domain: all 41 test domains are held; sharing one" >&2
  export ROS_DOMAIN_ID=$((1 + start))
}
unav_pick_test_domain

# wait_for_topic LINE [TIMEOUT_S]: polls `unav topic list -t` until it has the line LINE (e.g.
# "/clock [rosgraph_msgs/msg/Clock]") and prints that listing. A process just launched may take
# seconds to create its participant on a loaded machine (CI: the physics server had not announced
# its topics within one 3 s listing); returns 1 with the last listing after TIMEOUT_S (60).
wait_for_topic() {
  local end=$((SECONDS + ${2:-60})) topics
  while :; do
    topics=$(unav topic list -t)
    if grep -qxF -- "$1" <<<"$topics"; then printf '%s\n' "$topics"; return 0; fi
    if [ $SECONDS -ge $end ]; then printf '%s\n' "$topics"; return 1; fi
    sleep 0.5
  done
}
