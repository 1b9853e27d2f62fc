// Start `stvm lsp` the way editors/vscode/extension.js does (its serverOptions(), with a stub of
// the few `vscode` calls it makes to read the settings) and talk to it through vscode-jsonrpc,
// the JSON-RPC layer of vscode-languageclient: initialize, open a file, hover, definition,
// completion. Prints one JSON line with the answers. Usage:
//   node vscode_client.js EXTENSION_DIR FILE LINE CHARACTER SETTINGS_JSON
const path = require("path");
const fs = require("fs");
const cp = require("child_process");
const Module = require("module");

const [extensionArg, file, line, character, settingsJson] = process.argv.slice(2);
const extensionDir = path.resolve(extensionArg);
const settings = JSON.parse(settingsJson || "{}");
const vscodeStub = {
  workspace: {
    getConfiguration: () => ({ get: (key, fallback) => (key in settings ? settings[key] : fallback) }),
    workspaceFolders: [{ uri: { fsPath: path.dirname(file) } }],
    createFileSystemWatcher: () => ({}),
  },
};
const load = Module._load;
Module._load = function (request, parent, isMain) {
  return request === "vscode" ? vscodeStub : load.apply(this, arguments);
};
const extension = require(path.join(extensionDir, "extension.js"));
const rpc = require(path.join(extensionDir, "node_modules", "vscode-jsonrpc", "node"));

const options = extension.serverOptions();
const child = cp.spawn(options.command, options.args, { cwd: options.options.cwd, stdio: ["pipe", "pipe", "inherit"] });
const connection = rpc.createMessageConnection(new rpc.StreamMessageReader(child.stdout), new rpc.StreamMessageWriter(child.stdin));
const uri = "file://" + path.resolve(file);
let diagnostics = null;
connection.onNotification("textDocument/publishDiagnostics", (params) => {
  if (params.uri === uri) diagnostics = params.diagnostics;
});
connection.listen();

(async () => {
  const init = await connection.sendRequest("initialize", { processId: process.pid, rootUri: null, capabilities: {} });
  connection.sendNotification("initialized", {});
  connection.sendNotification("textDocument/didOpen", {
    textDocument: { uri, languageId: "structured-text", version: 1, text: fs.readFileSync(file, "utf8") },
  });
  const position = { line: Number(line), character: Number(character) };
  const at = { textDocument: { uri }, position };
  const hover = await connection.sendRequest("textDocument/hover", at);
  const definition = await connection.sendRequest("textDocument/definition", at);
  const completion = await connection.sendRequest("textDocument/completion", at);
  await connection.sendRequest("shutdown");
  connection.sendNotification("exit");
  console.log(JSON.stringify({
    args: options.args, selector: extension.clientOptions().documentSelector, capabilities: Object.keys(init.capabilities),
    hover, definition, completion: completion.items.length, diagnostics,
  }));
  setTimeout(() => process.exit(0), 200);
})().catch((err) => { console.error(err); process.exit(1); });
