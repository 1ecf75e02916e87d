// The C# side of callback_cost_bench: connects to hapticd (first argument) for the seconds given,
// and prints, one per line, each State's time from the kernel's receive stamp to the first line of
// its OnState callback (µs).
using System;
using System.Collections.Generic;
using System.Globalization;
using System.Threading;
using Hapticd;

static class CallbackCost
{
    static int Main(string[] args)
    {
        var delays = new List<double>(100000);
        var gate = new object();
        using (var client = new Client(new ClientConfig { ServerAddress = args[0], ClientName = "callback-cost-cs" }))
        {
            client.OnState(state =>
            {
                long now = Client.SteadyClockNs();
                if (state.ArrivedAtNs == 0) return;
                lock (gate) delays.Add((now - state.ArrivedAtNs) * 1e-3);
            });
            Thread.Sleep(TimeSpan.FromSeconds(double.Parse(args[1], CultureInfo.InvariantCulture)));
            client.OnState(null);
        }
        var text = new System.Text.StringBuilder();
        foreach (var d in delays) text.Append(d.ToString("R", CultureInfo.InvariantCulture)).Append('\n');
        Console.Write(text.ToString());
        return 0;
    }
}
