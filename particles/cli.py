"""The ``particles`` command line."""

import argparse
import sys

__all__ = ["main"]


def _tour(args):
    from .tour import run_tour

    run_tour(args.out)
    return 0


def _study(args):
    from .studies.report import write_study

    write_study(args.name, args.out)
    return 0


def _site(args):
    from .site import build_site

    build_site(args.out, args.lectures, timeout=args.timeout)
    return 0


def build_parser():
    parser = argparse.ArgumentParser(
        prog="particles",
        description="Particle systems and mass-spring simulation: the course package's tools.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    tour = sub.add_parser("tour", help="run the course tour: figures, animations and tables")
    tour.add_argument("--out", default="out", help="output folder (default: out)")
    tour.set_defaults(run=_tour)

    study = sub.add_parser("study", help="run a measured study and write its figure (PNG, SVG) and table (CSV)")
    study.add_argument("name", choices=["order", "stability", "provot", "discretization", "all"])
    study.add_argument("--out", default="out/studies", help="output folder (default: out/studies)")
    study.set_defaults(run=_study)

    site = sub.add_parser("site", help="execute the lectures and write a static HTML course site")
    site.add_argument("--out", default="site", help="output folder (default: site)")
    site.add_argument("--lectures", default="lectures", help="folder of NN_topic.ipynb lectures")
    site.add_argument("--timeout", type=float, default=600, help="seconds allowed per cell")
    site.set_defaults(run=_site)
    return parser


def main(argv=None):
    """Entry point of the ``particles`` console script."""
    args = build_parser().parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())
