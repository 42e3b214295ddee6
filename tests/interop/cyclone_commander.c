/* Test peer: a CycloneDDS ECU that writes one Manual command (open, 10 %) for the valve given,
 * prints "sent", then waits to be killed, so a test can make a commander of another vendor die
 * the hard way. Usage: cyclone_commander DOMAIN SERIAL
 *
 * It writes only once the gateway knows it, as docs/topics.md asks of every ECU: commands are
 * VOLATILE, and a gateway that has not yet matched this writer would drop what it wrote; this
 * side matching first proves nothing, matching is not symmetric in time. The gateway's
 * presence (TRANSIENT_LOCAL) reaching this participant shows the gateway has taken in its
 * endpoints. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "dds/dds.h"
#include "valve.h"

int main(int argc, char** argv) {
  if (argc != 3) return 2;
  const dds_entity_t participant = dds_create_participant(atoi(argv[1]), NULL, NULL);
  if (participant < 0) return 1;
  const dds_entity_t topic =
      dds_create_topic(participant, &teejet_ValveCommand_desc, "teejet/valve/command", NULL, NULL);
  dds_qos_t* qos = dds_create_qos();
  dds_qset_reliability(qos, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_history(qos, DDS_HISTORY_KEEP_ALL, 0);
  dds_qset_liveliness(qos, DDS_LIVELINESS_AUTOMATIC, DDS_SECS(2));
  const dds_entity_t writer = dds_create_writer(participant, topic, qos, NULL);
  dds_delete_qos(qos);
  if (writer < 0) return 1;

  const dds_entity_t presence_topic = dds_create_topic(participant, &teejet_ValvePresence_desc,
                                                       "teejet/valve/presence", NULL, NULL);
  dds_qos_t* state = dds_create_qos();
  dds_qset_reliability(state, DDS_RELIABILITY_RELIABLE, DDS_SECS(1));
  dds_qset_durability(state, DDS_DURABILITY_TRANSIENT_LOCAL);
  const dds_entity_t presence = dds_create_reader(participant, presence_topic, state, NULL);
  dds_delete_qos(state);
  if (presence < 0) return 1;

  dds_publication_matched_status_t matched;
  int known = 0;
  const dds_time_t give_up = dds_time() + DDS_SECS(30);
  do {
    if (dds_time() > give_up) {
      fputs("cyclone_commander: no gateway matched the command writer within 30 s\n", stderr);
      return 2;
    }
    dds_sleepfor(DDS_MSECS(10));
    dds_get_publication_matched_status(writer, &matched);
    void* samples[1] = {NULL};
    dds_sample_info_t info[1];
    const int taken = dds_take(presence, samples, info, 1, 1);
    if (taken > 0) {
      known = 1;
      dds_return_loan(presence, samples, taken);
    }
  } while (matched.current_count == 0 || !known);

  teejet_ValveCommand command;
  memset(&command, 0, sizeof command);
  command.serial = (uint32_t)strtoul(argv[2], NULL, 10);
  command.command_id = 1;
  strcpy(command.origin, "cyclone-commander");
  command.kind = teejet_COMMAND_MANUAL;
  command.speed_percent = 10;
  command.direction = teejet_DIRECTION_OPEN;
  if (dds_write(writer, &command) != DDS_RETCODE_OK) return 1;
  puts("sent");
  fflush(stdout);
  for (;;) dds_sleepfor(DDS_SECS(60));
}
