"""``particles demo NAME``: a particle-effect animation simulated and written as a GIF."""


def run(args):
    from ..demos import DEMOS, write_demo

    names = list(DEMOS) if args.name == "all" else [args.name]
    for name in names:  # a loop over demos
        data, paths = write_demo(name, args.out, seconds=args.seconds, fps=args.fps, seed=args.seed,
                                 html=args.html)
        info = ", ".join(f"{k} {v}" for k, v in data.info.items())
        print(f"{name}: {len(data)} frames, {info} -> {', '.join(str(p) for p in paths)}")
    return 0


def register(commands):
    from ..demos import DEMOS

    listing = "; ".join(f"{name}: {demo.description}" for name, demo in DEMOS.items())
    demo = commands.add_parser("demo", help="write a particle-effect animation (GIF) to a folder",
                               description=f"Simulate a demo and write NAME.gif. Demos: {listing}.")
    demo.add_argument("name", choices=[*DEMOS, "all"], metavar="NAME",
                      help=f"one of {', '.join(DEMOS)}, or all")
    demo.add_argument("--out", default="out", help="output folder (default: out)")
    demo.add_argument("--seconds", type=float, default=None, help="simulated time (default: the demo's)")
    demo.add_argument("--fps", type=int, default=None, help="frames per second (default: the demo's)")
    demo.add_argument("--seed", type=int, default=0, help="random seed (default: 0)")
    demo.add_argument("--html", action="store_true", help="also write NAME.html, an HTML/JavaScript player")
    demo.set_defaults(run=run)
