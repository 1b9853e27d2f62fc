// stvm for VS Code.
//  * Language server: starts `stvm lsp` (the `stvm.command` setting, plus `--sysmac` for the
//    `stvm.dialect` and `stvm.sysmac` settings) for .st, TwinCAT (.TcPOU/.TcDUT/.TcGVL/.TcIO) and
//    PLCopen XML files: diagnostics while typing, hover, definition, references, completion,
//    signature help, rename, symbols, semantic tokens, folding (docs/editor.md).
//  * Debugger: starts `stvm dap` as the debug adapter of every `stvm` launch configuration.
//  * Commands: run, trace, lint and test the current file's project, in a terminal task.
//  * `stvm-rule:SA201` links of lint findings open `stvm lint --explain SA201`.
// Everything else is in stvm itself.
const vscode = require("vscode");
const cp = require("child_process");

const LANGUAGES = ["structured-text", "twincat-xml", "plcopen-xml"];
let client;

function config() {
  return vscode.workspace.getConfiguration("stvm");
}

function stvmCommand() {
  const command = config().get("command", ["stvm"]);
  return command.length ? command : ["stvm"];
}

// --sysmac NAME=VALUE for the dialect and the extra settings
function settingArgs() {
  const out = [];
  const dialect = config().get("dialect", "");
  if (dialect) {
    out.push("--sysmac", `dialect=${dialect}`);
  }
  for (const item of config().get("sysmac", [])) {
    out.push("--sysmac", item);
  }
  return out;
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

function serverOptions() {
  const [executable, ...args] = stvmCommand();
  return { command: executable, args: [...args, "lsp", ...settingArgs()], options: { cwd: workspaceFolderPath() } };
}

function clientOptions() {
  return {
    documentSelector: LANGUAGES.map((language) => ({ scheme: "file", language })),
    diagnosticCollectionName: "stvm",
    // live values (inlay hints) read from a running `stvm run --opcua` (stvm/lsp/live.py)
    initializationOptions: {
      liveValues: { enable: config().get("liveValues.enable", true), endpoint: config().get("liveValues.endpoint", "opc.tcp://127.0.0.1:4840") },
    },
    synchronize: { fileEvents: vscode.workspace.createFileSystemWatcher("**/{stvm.toml,*.st,*.Tc*,*.xml}") },
  };
}

function startLanguageServer(context) {
  if (!config().get("lint.enable", true)) {
    return;
  }
  let languageclient;
  try {
    languageclient = require("vscode-languageclient/node");
  } catch (err) {
    vscode.window.showWarningMessage("stvm: the packaged extension carries vscode-languageclient; from a checkout run `npm install` in editors/vscode.");
    return;
  }
  client = new languageclient.LanguageClient("stvm", "stvm language server", serverOptions(), clientOptions());
  client.start();
  context.subscriptions.push({ dispose: () => client && client.stop() });
}

// run / trace / lint / test the file in the editor (a file of a folder with stvm.toml is that
// project), as a task in the terminal panel: no shell, so paths need no quoting
function runStvm(subcommand, extra) {
  const editor = vscode.window.activeTextEditor;
  if (!editor || !LANGUAGES.includes(editor.document.languageId)) {
    vscode.window.showInformationMessage(`stvm ${subcommand}: open a Structured Text, TwinCAT or PLCopen file first.`);
    return;
  }
  const file = editor.document.uri.fsPath;
  const [executable, ...args] = stvmCommand();
  const folder = vscode.workspace.getWorkspaceFolder(editor.document.uri);
  const execution = new vscode.ProcessExecution(executable, [...args, subcommand, ...extra, ...settingArgs(), file],
    { cwd: folder ? folder.uri.fsPath : undefined });
  const task = new vscode.Task({ type: "stvm", subcommand }, folder || vscode.TaskScope.Workspace,
    `${subcommand} ${editor.document.fileName.split(/[\\/]/).pop()}`, "stvm", execution, []);
  task.presentationOptions = { reveal: vscode.TaskRevealKind.Always, clear: true };
  return editor.document.save().then(() => vscode.tasks.executeTask(task));
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
    vscode.workspace.registerTextDocumentContentProvider("stvm-rule", ruleProvider),
    vscode.commands.registerCommand("stvm.run", () => runStvm("run", [])),
    vscode.commands.registerCommand("stvm.trace", () => runStvm("trace", [])),
    vscode.commands.registerCommand("stvm.lint", () => runStvm("lint", [])),
    vscode.commands.registerCommand("stvm.test", () => runStvm("test", [])),
    vscode.commands.registerCommand("stvm.restartServer", () => (client ? client.restart() : startLanguageServer(context))),
    vscode.workspace.onDidChangeConfiguration((event) => {
      if (event.affectsConfiguration("stvm") && client) {
        vscode.window.showInformationMessage("stvm: settings changed; restarting the language server.");
        client.stop().then(() => { client = undefined; startLanguageServer(context); });
      }
    })
  );
  startLanguageServer(context);
}

function deactivate() {
  return client ? client.stop() : undefined;
}

// serverOptions/clientOptions are exported for tests/lsp/test_vscode_extension.py, which starts
// the server with the command line built here and talks to it through the client's JSON-RPC
module.exports = { activate, deactivate, serverOptions, clientOptions, settingArgs };
