# Sourced by the set-up scripts: fetch_pinned_wheel NAME SHA256 REQUIREMENT [PIP_ARGS...] downloads the
# wheel NAME (once, into CACHE_DIR) with `python3 -m pip download --no-deps`, checks it against SHA256
# and sets WHEEL to its path; a wheel that does not match is deleted and the script stops.
# Needs CACHE_DIR and a `log` function.
fetch_pinned_wheel() {
    local name="$1" sha="$2" req="$3"
    shift 3
    mkdir -p "$CACHE_DIR"
    WHEEL="$CACHE_DIR/$name"
    if [ ! -f "$WHEEL" ] || ! echo "$sha  $WHEEL" | sha256sum -c --status; then
        log "downloading $name"
        rm -f "$WHEEL"
        python3 -m pip download --quiet --no-deps --disable-pip-version-check "$@" "$req" -d "$CACHE_DIR"
    fi
    if ! echo "$sha  $WHEEL" | sha256sum -c --status; then
        log "checksum mismatch for $WHEEL (expected $sha); refusing to use it"
        rm -f "$WHEEL"
        exit 1
    fi
}
