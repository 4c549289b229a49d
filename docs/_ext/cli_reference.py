"""``.. autobones-cli::``: the command-line reference, generated from the argparse parser.

One section per command holding exactly what ``autobones COMMAND --help`` prints (a literal block, so
the epilogs' hand-aligned examples stay aligned; sphinx-argparse would read them as reStructuredText).
"""
import os

from docutils import nodes
from sphinx.util.docutils import SphinxDirective


class CliReference(SphinxDirective):
    def run(self):
        os.environ["COLUMNS"] = "100"  # argparse wraps to the terminal: fix it so the pages do not depend on one
        from autobones.cli.parser import build_parser

        parser = build_parser()
        out = [self._section("autobones", "autobones", parser.format_help())]
        for name, sub in parser.command_parsers.items():
            out.append(self._section(f"autobones {name}", f"cli-{name}", sub.format_help()))
        return out

    def _section(self, title, ident, text):
        section = nodes.section(ids=[ident])
        section += nodes.title(text=title)
        block = nodes.literal_block(text, text)
        block["language"] = "text"
        section += block
        return section


def setup(app):
    app.add_directive("autobones-cli", CliReference)
    return {"parallel_read_safe": True, "version": "1"}
