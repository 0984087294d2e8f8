"""The ``particles`` command line."""

import argparse
import sys

__all__ = ["main"]


def _tour(args):
    from .tour import run_tour

    run_tour(args.out)
    return 0


def _demo(args):
    from .demos import DEMOS, write_demo

    names = list(DEMOS) if args.name == "all" else [args.name]
    for name in names:  # a loop over demos
        data, paths = write_demo(name, args.out, seconds=args.seconds, fps=args.fps, seed=args.seed,
                                 html=args.html)
        info = ", ".join(f"{k} {v}" for k, v in data.info.items())
        print(f"{name}: {len(data)} frames, {info} -> {', '.join(str(p) for p in paths)}")
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
    from .demos import DEMOS

    parser = argparse.ArgumentParser(
        prog="particles",
        description="Particle systems and mass-spring simulation: the course package's tools.",
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    tour = sub.add_parser("tour", help="run the course tour: figures, animations and tables")
    tour.add_argument("--out", default="out", help="output folder (default: out)")
    tour.set_defaults(run=_tour)

    listing = "; ".join(f"{name}: {demo.description}" for name, demo in DEMOS.items())
    demo = sub.add_parser("demo", help="write a particle-effect animation (GIF) to a folder",
                          description=f"Simulate a demo and write NAME.gif. Demos: {listing}.")
    demo.add_argument("name", choices=[*DEMOS, "all"], metavar="NAME",
                      help=f"one of {', '.join(DEMOS)}, or all")
    demo.add_argument("--out", default="out", help="output folder (default: out)")
    demo.add_argument("--seconds", type=float, default=None, help="simulated time (default: the demo's)")
    demo.add_argument("--fps", type=int, default=None, help="frames per second (default: the demo's)")
    demo.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    demo.add_argument("--html", action="store_true", help="also write NAME.html, an HTML/JavaScript player")
    demo.set_defaults(run=_demo)

    study = sub.add_parser("study", help="run a measured study and write its figure (PNG, SVG) and table (CSV)")
    study.add_argument("name", choices=["order", "stability", "provot", "discretization", "bounce", "all"])
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
