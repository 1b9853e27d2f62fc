// stvm debugger for VS Code: starts `stvm dap` (the command is the `stvm.command` setting) as the
// debug adapter of every `stvm` launch configuration. Everything else is in stvm itself.
const vscode = require("vscode");

function activate(context) {
  context.subscriptions.push(
    vscode.debug.registerDebugAdapterDescriptorFactory("stvm", {
      createDebugAdapterDescriptor(session) {
        const command = vscode.workspace.getConfiguration("stvm").get("command", ["stvm"]);
        const [executable, ...args] = command.length ? command : ["stvm"];
        const folder = session.workspaceFolder ? session.workspaceFolder.uri.fsPath : undefined;
        return new vscode.DebugAdapterExecutable(executable, [...args, "dap"], { cwd: folder });
      },
    })
  );
}

function deactivate() {}

module.exports = { activate, deactivate };
