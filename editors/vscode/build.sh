#!/usr/bin/env bash
# Package the VS Code extension as a .vsix (editors/vscode/stvm-<version>.vsix):
#   editors/vscode/build.sh [OUT.vsix]
# Needs node >= 20 and npm (the npm registry for vscode-languageclient and @vscode/vsce).
# node_modules/ and the .vsix stay out of git (.gitignore).
set -euo pipefail
cd "$(dirname "$0")"
node --check extension.js
for grammar in syntaxes/*.json language-configuration*.json package.json; do
    node -e 'JSON.parse(require("fs").readFileSync(process.argv[1], "utf8"))' "$grammar"
done
if [ -f package-lock.json ]; then
    npm ci --no-audit --no-fund --loglevel=error
else
    npm install --no-audit --no-fund --loglevel=error
fi
version="$(node -p 'require("./package.json").version')"
out="${1:-stvm-$version.vsix}"
npx --no-install vsce package --skip-license --allow-missing-repository --out "$out"
echo "built $(pwd)/$out"
