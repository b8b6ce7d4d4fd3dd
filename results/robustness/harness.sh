# The harness of the bad-input rounds 5 and 6 (results/robustness/round5.sh, round6.sh), sourced by
# each after it has set BP (the binary), OUT (the .tsv to write), BEFORE (a file holding the scratch
# folder's listing) and `snapshot` (the listing command): `case_` runs one case and records it,
# `summary` prints the verdicts' counts.
printf 'case\tcommand\texpect\texit\tseconds\tpanicked\tleft_behind\tverdict\tfirst_line\n' > "$OUT"
declare -A COUNT=()
n=0
# case_ NAME EXPECT COMMAND...: EXPECT is "accept" or "refuse:W1;W2;..." (each W an ERE).
case_() {
    local name=$1 expect=$2; shift 2
    n=$((n + 1))
    local t0=$(date +%s.%N)
    timeout 60 "$@" > stdout.txt 2> stderr.txt < /dev/null
    local rc=$?
    local secs=$(echo "$(date +%s.%N) - $t0" | bc)
    local said=$(cat stderr.txt stdout.txt)
    local panicked=no
    grep -q "panicked" stderr.txt stdout.txt && panicked=yes
    local first=$(grep -m1 . stderr.txt | cut -c1-300 | tr '\t' ' ')
    rm -f stdout.txt stderr.txt
    local left=no
    if ! diff -q <(snapshot) "$BEFORE" >/dev/null; then
        left=$(diff <(snapshot) "$BEFORE" | grep '^[<>]' | head -3 | tr '\n' ' ')
    fi
    local verdict=clear
    if [ "$panicked" = yes ]; then verdict=panic
    elif [ $rc -eq 124 ] || [ $rc -eq 137 ]; then verdict=hang
    elif [ "${expect%%:*}" = refuse ] && [ "$left" != no ]; then verdict=partial
    elif [ "${expect%%:*}" = refuse ] && [ $rc -eq 0 ]; then verdict=accepted
    elif [ "$expect" = accept ] && [ $rc -ne 0 ]; then verdict=refused
    elif [ "${expect%%:*}" = refuse ]; then
        local IFS=';'
        for w in ${expect#refuse:}; do
            printf '%s' "$said" | grep -Eq -- "$w" || verdict=misworded
        done
    fi
    # Put the folder back as it was for the next case (a case meant to write may).
    if [ "$left" != no ]; then
        for p in $(diff <(snapshot) "$BEFORE" | grep '^<' | awk '{print $2}'); do rm -rf "$p"; done
    fi
    COUNT[$verdict]=$(( ${COUNT[$verdict]:-0} + 1 ))
    local cmd=$(printf '%q ' "$@" | sed "s#$BP#blockpuzzle#g")
    printf '%s\t%s\t%s\t%s\t%.2f\t%s\t%s\t%s\t%s\n' "$name" "$cmd" "$expect" "$rc" "$secs" "$panicked" "$left" \
        "$verdict" "$first" >> "$OUT"
}

# The number of cases and each verdict's count.
summary() {
    echo "$n cases -> $OUT"
    for v in clear panic hang partial accepted refused misworded; do printf '%s %s\n' "$v" "${COUNT[$v]:-0}"; done
}
