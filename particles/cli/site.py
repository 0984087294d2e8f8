"""``particles site``: the lectures executed and written as a static HTML course site."""

import sys


def run(args):
    from ..course.release.site import build_site

    try:
        build_site(args.out, args.lectures, timeout=args.timeout)
    except ValueError as error:  # a missing or empty lectures folder
        print(f"particles site: {error}", file=sys.stderr)
        return 2
    return 0


def register(commands):
    site = commands.add_parser("site", help="execute the lectures and write a static HTML course site")
    site.add_argument("--out", default="site", help="output folder (default: site)")
    site.add_argument("--lectures", default="lectures", help="folder of NN_topic.ipynb lectures")
    site.add_argument("--timeout", type=float, default=600, help="seconds allowed per cell")
    site.set_defaults(run=run)
