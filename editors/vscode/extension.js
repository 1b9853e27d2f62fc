// stvm for VS Code.
//  * Debugger: starts `stvm dap` (the command is the `stvm.command` setting) as the debug adapter
//    of every `stvm` launch configuration.
//  * Diagnostics: starts `stvm lsp`, a language server that publishes the checker's errors and the
//    `stvm lint` findings of a .st file when it is opened or saved. A finding's code (SA201 …)
//    links to its explanation: docs/lint.md of the repository, or a read-only page produced by
//    `stvm lint --explain CODE` (the `stvm-rule:` scheme below).
// Everything else is in stvm itself.
const vscode = require("vscode");
const cp = require("child_process");

let client;

function stvmCommand() {
  const command = vscode.workspace.getConfiguration("stvm").get("command", ["stvm"]);
  return command.length ? command : ["stvm"];
}

function workspaceFolderPath() {
  const folders = vscode.workspace.workspaceFolders;
  return folders && folders.length ? folders[0].uri.fsPath : undefined;
}

// `stvm-rule:SA201` → the text of `stvm lint --explain SA201`
const ruleProvider = {
  provideTextDocumentContent(uri) {
    const code = uri.path.replace(/\.md$/, "");
    const [executable, ...args] = stvmCommand();
    return new Promise((resolve) => {
      cp.execFile(executable, [...args, "lint", "--explain", code], { cwd: workspaceFolderPath() },
        (error, stdout, stderr) => resolve(error && !stdout ? `stvm lint --explain ${code} failed:\n${stderr || error}` : stdout));
    });
  },
};

function startLanguageServer(context) {
  if (!vscode.workspace.getConfiguration("stvm").get("lint.enable", true)) {
    return;
  }
  let languageclient;
  try {
    languageclient = require("vscode-languageclient/node");
  } catch (err) {
    vscode.window.showWarningMessage("stvm: run `npm install` in editors/vscode to get check and lint diagnostics.");
    return;
  }
  const [executable, ...args] = stvmCommand();
  const serverOptions = { command: executable, args: [...args, "lsp"], options: { cwd: workspaceFolderPath() } };
  const clientOptions = {
    documentSelector: [{ scheme: "file", language: "structured-text" }],
    diagnosticCollectionName: "stvm",
  };
  client = new languageclient.LanguageClient("stvm", "stvm (check and lint)", serverOptions, clientOptions);
  client.start();
  context.subscriptions.push({ dispose: () => client && client.stop() });
}

function activate(context) {
  context.subscriptions.push(
    vscode.debug.registerDebugAdapterDescriptorFactory("stvm", {
      createDebugAdapterDescriptor(session) {
        const [executable, ...args] = stvmCommand();
        const folder = session.workspaceFolder ? session.workspaceFolder.uri.fsPath : undefined;
        return new vscode.DebugAdapterExecutable(executable, [...args, "dap"], { cwd: folder });
      },
    }),
    vscode.workspace.registerTextDocumentContentProvider("stvm-rule", ruleProvider)
  );
  startLanguageServer(context);
}

function deactivate() {
  return client ? client.stop() : undefined;
}

module.exports = { activate, deactivate };
