"""``parakin kernels``: the cache of compiled kernels."""

from __future__ import annotations

from parakin import kernels


def cmd_kernels(args) -> int:
    """``parakin kernels``: where compiled code is cached, what is there; ``--clear`` empties it."""
    from parakin.kernels import store

    root = store.root()
    if args.clear:
        freed = store.clear()
        print(f"parakin kernels: removed {freed / 1e6:.1f} MB of compiled code from {root}")
        return 0
    status = store.status()
    on = "on" if kernels.enabled() else "off (the numpy path)"
    print(f"cache: {status['root'] or 'none writable'}; compiled path {on}")
    for b in status["builds"]:
        what = f"{b['name']} ({b['hash']})" if b["hash"] else b["name"]
        print(f"  {what:<50} {b['files']:>4} files {b['bytes'] / 1e6:8.1f} MB")
    return 0


def add_kernels(sub) -> None:
    p = sub.add_parser(
        "kernels",
        help="the cache of compiled kernels: status (default) or --clear",
        func=cmd_kernels,
    )
    p.add_argument("--status", action="store_true", help="list the cached builds (default)")
    p.add_argument("--clear", action="store_true", help="remove every cached build")
