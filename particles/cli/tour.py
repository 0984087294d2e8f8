"""``particles tour``: the course tour, its figures, animations and tables written to a folder."""


def run(args):
    from ..tour import run_tour

    run_tour(args.out)
    return 0


def register(commands):
    tour = commands.add_parser("tour", help="run the course tour: figures, animations and tables")
    tour.add_argument("--out", default="out", help="output folder (default: out)")
    tour.set_defaults(run=run)
