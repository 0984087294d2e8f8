"""``particles study NAME``: a measured study, its figure (PNG, SVG) and table (CSV)."""


def run(args):
    from ..studies.report import write_study

    write_study(args.name, args.out)
    return 0


def register(commands):
    study = commands.add_parser("study", help="run a measured study and write its figure (PNG, SVG) and table (CSV)")
    study.add_argument("name", choices=["order", "stability", "provot", "discretization", "bounce", "all"])
    study.add_argument("--out", default="out/studies", help="output folder (default: out/studies)")
    study.set_defaults(run=run)
