// The C# side of callback_cost_bench: connects to hapticd's HTTP face (first argument) with the
// managed client for the seconds given, and prints its CPU time per sample received (after 0.5 s
// of warm-up) as "cpu_us_per_sample V samples N", then, one per line, each State's time from the
// client's own read of the socket (State.ReceivedAtNs: .NET reads no kernel stamp) to the first
// line of its OnState callback (µs).
using System;
using System.Collections.Generic;
using System.Diagnostics;
using System.Globalization;
using System.Threading;
using Hapticd;

static class CallbackCost
{
    static int Main(string[] args)
    {
        var delays = new List<double>(100000);
        long calls = 0;
        var gate = new object();
        var self = Process.GetCurrentProcess();
        double cpuUs;
        long samples;
        using (var client = new Client(new ClientConfig { ServerAddress = args[0], ClientName = "callback-cost-cs" }))
        {
            client.OnState(state =>
            {
                long now = Client.SteadyClockNs();
                lock (gate)
                {
                    ++calls;
                    delays.Add((now - state.ReceivedAtNs) * 1e-3);
                }
            });
            Thread.Sleep(500);  // warm-up: the JIT has compiled the receive path
            long callsBefore;
            lock (gate) callsBefore = calls;
            self.Refresh();
            var cpuBefore = self.TotalProcessorTime;
            Thread.Sleep(TimeSpan.FromSeconds(double.Parse(args[1], CultureInfo.InvariantCulture)));
            self.Refresh();
            cpuUs = (self.TotalProcessorTime - cpuBefore).TotalMilliseconds * 1e3;
            lock (gate) samples = calls - callsBefore;
            client.OnState(null);
        }
        var text = new System.Text.StringBuilder();
        text.Append("cpu_us_per_sample ").Append((samples > 0 ? cpuUs / samples : 0.0).ToString("F3", CultureInfo.InvariantCulture))
            .Append(" samples ").Append(samples).Append('\n');
        foreach (var d in delays) text.Append(d.ToString("R", CultureInfo.InvariantCulture)).Append('\n');
        Console.Write(text.ToString());
        return 0;
    }
}
